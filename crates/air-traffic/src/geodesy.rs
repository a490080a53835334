//! WGS-84 geodetic coordinates to a local east-north-up frame (through Earth-centred,
//! Earth-fixed coordinates; NIMA TR8350.2 for the ellipsoid, the usual rotation for ENU).

use serde::{Deserialize, Serialize};
use tracker_model::{Error as ModelError, ensure_in_range};

use crate::error::Result;

/// WGS-84 semi-major axis, metres.
const A: f64 = 6_378_137.0;
/// WGS-84 flattening.
const F: f64 = 1.0 / 298.257_223_563;

/// A local east-north-up frame with its origin on the ellipsoid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnuFrame {
    /// Origin latitude, degrees.
    pub latitude_deg: f64,
    /// Origin longitude, degrees.
    pub longitude_deg: f64,
}

fn ecef(lat_deg: f64, lon_deg: f64, height_m: f64) -> [f64; 3] {
    let e2 = F * (2.0 - F);
    let (lat, lon) = (lat_deg.to_radians(), lon_deg.to_radians());
    let (sl, cl) = lat.sin_cos();
    let (so, co) = lon.sin_cos();
    let n = A / (1.0 - e2 * sl * sl).sqrt();
    [
        (n + height_m) * cl * co,
        (n + height_m) * cl * so,
        (n * (1.0 - e2) + height_m) * sl,
    ]
}

impl EnuFrame {
    /// A frame at a checked latitude (−90° to 90°) and longitude (−180° to 180°).
    pub fn new(latitude_deg: f64, longitude_deg: f64) -> Result<Self> {
        ensure_in_range(latitude_deg, -90.0, 90.0, "latitude_deg")?;
        ensure_in_range(longitude_deg, -180.0, 180.0, "longitude_deg")?;
        Ok(Self {
            latitude_deg,
            longitude_deg,
        })
    }

    /// East, north and up, metres, of a point at this latitude, longitude and height above
    /// the ellipsoid.
    pub fn to_enu(&self, lat_deg: f64, lon_deg: f64, height_m: f64) -> Result<[f64; 3]> {
        if ![lat_deg, lon_deg, height_m].iter().all(|v| v.is_finite()) {
            return Err(ModelError::NonFinite {
                what: "ADS-B position",
            }
            .into());
        }
        let p = ecef(lat_deg, lon_deg, height_m);
        let o = ecef(self.latitude_deg, self.longitude_deg, 0.0);
        let d = [p[0] - o[0], p[1] - o[1], p[2] - o[2]];
        let (lat, lon) = (
            self.latitude_deg.to_radians(),
            self.longitude_deg.to_radians(),
        );
        let (sl, cl) = lat.sin_cos();
        let (so, co) = lon.sin_cos();
        Ok([
            -so * d[0] + co * d[1],
            -sl * co * d[0] - sl * so * d[1] + cl * d[2],
            cl * co * d[0] + cl * so * d[1] + sl * d[2],
        ])
    }
}
