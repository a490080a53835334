//! A scene renderer for tests and scenarios: a textured ground plane seen by a calibrated
//! [`PinholeCamera`], slow illumination drift, swaying-texture clutter patches, glint flashes,
//! sensor noise, and moving people- and vehicle-sized shaded objects that cast shadows. It
//! returns each frame with its truth: object mask, cast-shadow mask, boxes and bearings.
//!
//! Objects are vertical cylinders (radius = half their width) drawn by their silhouette, a
//! billboard facing the camera, shaded across and up the body. A ground point lies in shadow
//! when the segment from it towards the sun passes through a cylinder, i.e. when its distance
//! to the cylinder's ground shadow axis (from the base, length height/tan(elevation), away
//! from the sun) is at most the radius. A shadow scales the ground's colour by
//! `shadow_factor`, keeping its chromaticity, as Horprasert's model assumes. All randomness
//! (textures, glints, noise) comes from the generator passed in.

use std::f64::consts::TAU;

use rand::{Rng, RngExt};
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};
use tracker_model::{BoundingBox, ensure_in_range, ensure_non_negative, ensure_positive};

use crate::camera::PinholeCamera;
use crate::error::Result;
use crate::frame::{PixelFormat, VideoFrame};

/// Scene-wide settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneConfig {
    /// The camera (its size is the frame size).
    pub camera: PinholeCamera,
    /// Grey or RGB output (grey is the BT.601 luma of the rendered colour).
    pub format: PixelFormat,
    /// Seconds per frame.
    pub frame_period_s: f64,
    /// Relative amplitude of the global illumination drift, gain 1 + A sin(2π t / P).
    pub drift_amplitude: f64,
    /// Period P of the drift, seconds.
    pub drift_period_s: f64,
    /// Number of swaying-texture clutter patches (foliage).
    pub n_sway_patches: usize,
    /// Sway amplitude, pixels.
    pub sway_amplitude_px: f64,
    /// Sway period, seconds.
    pub sway_period_s: f64,
    /// Expected glint flashes per frame (each a saturated disc of radius 1–2 px for one frame).
    pub glints_per_frame: f64,
    /// Standard deviation of the additive Gaussian sensor noise, grey levels.
    pub noise_sigma: f64,
    /// Sun azimuth, radians counter-clockwise from +x.
    pub sun_azimuth_rad: f64,
    /// Sun elevation above the horizon, radians.
    pub sun_elevation_rad: f64,
    /// Brightness of shadowed ground relative to lit ground.
    pub shadow_factor: f64,
}

impl SceneConfig {
    /// A 160 × 120 colour scene from a camera 6 m up, looking along +x, tilted down 25°.
    pub fn small() -> Self {
        Self {
            camera: PinholeCamera {
                width: 160,
                height: 120,
                fx: 150.0,
                fy: 150.0,
                cx: 79.5,
                cy: 59.5,
                position_m: [0.0, 0.0, 6.0],
                heading_rad: 0.0,
                tilt_rad: 25f64.to_radians(),
            },
            format: PixelFormat::Rgb,
            frame_period_s: 0.1,
            drift_amplitude: 0.1,
            drift_period_s: 120.0,
            n_sway_patches: 2,
            sway_amplitude_px: 2.0,
            sway_period_s: 2.0,
            glints_per_frame: 0.5,
            noise_sigma: 3.0,
            sun_azimuth_rad: 2.4,
            sun_elevation_rad: 0.7,
            shadow_factor: 0.55,
        }
    }

    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        self.camera.check()?;
        ensure_positive(self.frame_period_s, "frame_period_s")?;
        ensure_in_range(self.drift_amplitude, 0.0, 0.5, "drift_amplitude")?;
        ensure_positive(self.drift_period_s, "drift_period_s")?;
        ensure_non_negative(self.sway_amplitude_px, "sway_amplitude_px")?;
        ensure_positive(self.sway_period_s, "sway_period_s")?;
        ensure_non_negative(self.glints_per_frame, "glints_per_frame")?;
        ensure_non_negative(self.noise_sigma, "noise_sigma")?;
        ensure_in_range(self.sun_elevation_rad, 0.1, 1.5, "sun_elevation_rad")?;
        ensure_in_range(self.shadow_factor, 0.0, 1.0, "shadow_factor")?;
        if !self.sun_azimuth_rad.is_finite() {
            return Err(tracker_model::Error::NonFinite {
                what: "sun_azimuth_rad",
            }
            .into());
        }
        Ok(())
    }
}

/// Size class of an object.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectKind {
    /// 0.5 m wide, 1.75 m tall.
    Person,
    /// 4 m wide (seen side-on), 1.5 m tall.
    Vehicle,
}

impl ObjectKind {
    /// (width, height) in metres.
    pub fn size_m(self) -> (f64, f64) {
        match self {
            Self::Person => (0.5, 1.75),
            Self::Vehicle => (4.0, 1.5),
        }
    }
}

/// A moving object: ground position start + velocity · t while t ∈ [appear_s, vanish_s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneObject {
    /// Size class.
    pub kind: ObjectKind,
    /// Ground position at t = 0, metres.
    pub start_m: [f64; 2],
    /// Ground velocity, metres per second.
    pub velocity_mps: [f64; 2],
    /// Base colour (RGB).
    pub colour: [u8; 3],
    /// First time it is in the scene, seconds.
    pub appear_s: f64,
    /// Time it leaves, seconds.
    pub vanish_s: f64,
}

/// Value noise: a random lattice, bilinearly interpolated, wrapping.
#[derive(Debug, Clone)]
struct ValueNoise {
    n: usize,
    lattice: Vec<f32>,
}

impl ValueNoise {
    fn new(n: usize, rng: &mut impl Rng) -> Self {
        Self {
            n,
            lattice: (0..n * n).map(|_| rng.random::<f32>()).collect(),
        }
    }

    fn sample(&self, x: f64, y: f64) -> f64 {
        let (fx, fy) = (x.floor(), y.floor());
        let (tx, ty) = (x - fx, y - fy);
        let n = self.n as i64;
        let at = |i: i64, j: i64| {
            f64::from(self.lattice[(i.rem_euclid(n) * n + j.rem_euclid(n)) as usize])
        };
        let (i, j) = (fx as i64, fy as i64);
        let a = at(i, j) * (1.0 - tx) + at(i + 1, j) * tx;
        let b = at(i, j + 1) * (1.0 - tx) + at(i + 1, j + 1) * tx;
        a * (1.0 - ty) + b * ty
    }
}

#[derive(Debug, Clone)]
struct SwayPatch {
    u0: usize,
    v0: usize,
    w: usize,
    h: usize,
    phase: f64,
    noise: ValueNoise,
}

/// A rendered frame and its truth.
#[derive(Debug, Clone)]
pub struct RenderedFrame {
    /// The image.
    pub frame: VideoFrame,
    /// Row-major: pixel shows an object.
    pub truth: Vec<bool>,
    /// Row-major: pixel shows ground in an object's cast shadow (and no object).
    pub shadow: Vec<bool>,
    /// Per visible object: its index in the object list and the box of its visible pixels.
    pub boxes: Vec<(usize, BoundingBox)>,
    /// Per object in the scene (visible or not): index and world bearing from the camera.
    pub bearings_rad: Vec<(usize, f64)>,
}

/// A scene ready to render frame by frame.
#[derive(Debug, Clone)]
pub struct Scene {
    config: SceneConfig,
    objects: Vec<SceneObject>,
    /// Lit background colour per pixel before drift.
    base: Vec<[f64; 3]>,
    /// Ground point of each pixel's ray, or NaN above the horizon.
    ground: Vec<[f64; 2]>,
    rays: Vec<[f64; 3]>,
    patches: Vec<SwayPatch>,
}

impl Scene {
    /// Builds the textures from `rng`.
    pub fn new(config: SceneConfig, objects: Vec<SceneObject>, rng: &mut impl Rng) -> Result<Self> {
        config.check()?;
        let cam = config.camera;
        let (w, h) = (cam.width, cam.height);
        let coarse = ValueNoise::new(64, rng);
        let fine = ValueNoise::new(64, rng);
        let sky = ValueNoise::new(64, rng);
        let mut base = Vec::with_capacity(w * h);
        let mut ground = Vec::with_capacity(w * h);
        let mut rays = Vec::with_capacity(w * h);
        for v in 0..h {
            for u in 0..w {
                let d = cam.ray(u as f64, v as f64);
                rays.push(d);
                if d[2] < -1e-6 {
                    let s = -cam.position_m[2] / d[2];
                    let (gx, gy) = (cam.position_m[0] + s * d[0], cam.position_m[1] + s * d[1]);
                    ground.push([gx, gy]);
                    // Paving and grass: a coarse 2 m pattern and a fine 0.25 m texture.
                    let t = 0.55 * coarse.sample(gx / 2.0, gy / 2.0)
                        + 0.45 * fine.sample(gx * 4.0, gy * 4.0);
                    let g = 0.6 + 0.8 * t;
                    base.push([115.0 * g, 120.0 * g, 105.0 * g]);
                } else {
                    ground.push([f64::NAN, f64::NAN]);
                    // Building façades above the horizon.
                    let t = sky.sample(u as f64 / 6.0, v as f64 / 6.0);
                    base.push([150.0 + 60.0 * t, 140.0 + 60.0 * t, 130.0 + 60.0 * t]);
                }
            }
        }
        let mut patches = Vec::new();
        for _ in 0..config.n_sway_patches {
            let pw = (w / 6).max(2);
            let ph = (h / 5).max(2);
            let u0 = rng.random_range(0..=w - pw);
            let v0 = rng.random_range(0..=h - ph);
            patches.push(SwayPatch {
                u0,
                v0,
                w: pw,
                h: ph,
                phase: rng.random::<f64>() * TAU,
                noise: ValueNoise::new(32, rng),
            });
        }
        Ok(Self {
            config,
            objects,
            base,
            ground,
            rays,
            patches,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &SceneConfig {
        &self.config
    }

    /// Renders frame `k` (time k · frame_period_s); glints and noise are drawn from `rng`.
    pub fn render(&self, k: usize, rng: &mut impl Rng) -> Result<RenderedFrame> {
        let cfg = &self.config;
        let cam = cfg.camera;
        let (w, h) = (cam.width, cam.height);
        let t = k as f64 * cfg.frame_period_s;
        let gain = 1.0 + cfg.drift_amplitude * (TAU * t / cfg.drift_period_s).sin();
        let c = cam.position_m;
        let live = self.live_objects(t);
        let bearings_rad = live
            .iter()
            .map(|o| (o.idx, (o.p[1] - c[1]).atan2(o.p[0] - c[0])))
            .collect();
        let (sa, ca) = cfg.sun_azimuth_rad.sin_cos();
        let shadow_len = 1.0 / cfg.sun_elevation_rad.tan();
        let sway = cfg.sway_amplitude_px * (TAU * t / cfg.sway_period_s).sin();
        let mut rgb = vec![0f64; w * h * 3];
        let mut truth = vec![false; w * h];
        let mut shadow = vec![false; w * h];
        let mut owner = vec![usize::MAX; w * h];
        for i in 0..w * h {
            let col = if let Some((idx, col)) = self.nearest_surface(i, &live) {
                owner[i] = idx;
                truth[i] = true;
                col
            } else {
                let mut col = self.background(i, sway);
                let g = self.ground[i];
                if g[0].is_finite() && in_shadow(g, &live, (sa, ca), shadow_len) {
                    shadow[i] = true;
                    col = col.map(|v| v * cfg.shadow_factor);
                }
                col
            };
            for ch in 0..3 {
                rgb[i * 3 + ch] = col[ch] * gain;
            }
        }
        add_glints(&mut rgb, w, h, cfg.glints_per_frame, rng);
        let noise = Normal::new(0.0, cfg.noise_sigma.max(1e-12)).map_err(|e| {
            tracker_model::Error::InvalidParameter {
                name: "noise_sigma",
                reason: e.to_string(),
            }
        })?;
        let bytes: Vec<u8> = rgb
            .iter()
            .map(|&v| {
                let n = if cfg.noise_sigma > 0.0 {
                    noise.sample(rng)
                } else {
                    0.0
                };
                (v + n).round().clamp(0.0, 255.0) as u8
            })
            .collect();
        let mut frame = VideoFrame::new(w, h, PixelFormat::Rgb, bytes)?;
        if cfg.format == PixelFormat::Grey {
            frame = frame.to_grey();
        }
        let boxes = object_boxes(&live, &owner, w);
        Ok(RenderedFrame {
            frame,
            truth,
            shadow,
            boxes,
            bearings_rad,
        })
    }

    /// The objects present at time `t`: base point, camera-facing plane normal and lateral.
    fn live_objects(&self, t: f64) -> Vec<Live> {
        let c = self.config.camera.position_m;
        self.objects
            .iter()
            .enumerate()
            .filter(|(_, o)| t >= o.appear_s && t < o.vanish_s)
            .map(|(idx, o)| {
                let p = [
                    o.start_m[0] + o.velocity_mps[0] * t,
                    o.start_m[1] + o.velocity_mps[1] * t,
                ];
                let b = (p[1] - c[1]).atan2(p[0] - c[0]);
                let (sb, cb) = b.sin_cos();
                let (ow, oh) = o.kind.size_m();
                Live {
                    idx,
                    p,
                    n: [cb, sb],
                    lat: [-sb, cb],
                    half_w: ow / 2.0,
                    height: oh,
                    colour: o.colour.map(f64::from),
                }
            })
            .collect()
    }

    /// The nearest object surface along pixel `i`'s ray (ray casting against each object's
    /// camera-facing billboard), as (object index, shaded colour): cylinder shading across
    /// the body, lighter towards the top. `None` when the ray meets no object.
    fn nearest_surface(&self, i: usize, live: &[Live]) -> Option<(usize, [f64; 3])> {
        let c = self.config.camera.position_m;
        let d = self.rays[i];
        let mut best: Option<(f64, [f64; 3])> = None;
        let mut owner = usize::MAX;
        for o in live {
            let dn = d[0] * o.n[0] + d[1] * o.n[1];
            if dn <= 1e-9 {
                continue;
            }
            let s = ((o.p[0] - c[0]) * o.n[0] + (o.p[1] - c[1]) * o.n[1]) / dn;
            let hp = [c[0] + s * d[0], c[1] + s * d[1], c[2] + s * d[2]];
            let lat = (hp[0] - o.p[0]) * o.lat[0] + (hp[1] - o.p[1]) * o.lat[1];
            if s > 0.0
                && lat.abs() <= o.half_w
                && hp[2] >= 0.0
                && hp[2] <= o.height
                && best.is_none_or(|(bs, _)| s < bs)
            {
                // Cylinder shading across the body, lighter towards the top.
                let across = lat / o.half_w;
                let shade =
                    (0.55 + 0.45 * (1.0 - across * across).sqrt()) * (0.8 + 0.3 * hp[2] / o.height);
                best = Some((s, o.colour.map(|v| v * shade)));
                owner = o.idx;
            }
        }
        best.map(|(_, col)| (owner, col))
    }

    /// The lit background of pixel `i` before drift: the ground or façade texture, or a
    /// swaying clutter patch (value noise shifted by `sway`, less towards the patch's foot).
    fn background(&self, i: usize, sway: f64) -> [f64; 3] {
        let w = self.config.camera.width;
        let (u, v) = (i % w, i / w);
        let mut col = self.base[i];
        for p in &self.patches {
            if u >= p.u0 && u < p.u0 + p.w && v >= p.v0 && v < p.v0 + p.h {
                let s = sway * (1.0 - (v - p.v0) as f64 / p.h as f64) + p.phase;
                let n = p.noise.sample((u as f64 + s) / 2.0, v as f64 / 2.0);
                let g = 0.5 + 1.0 * n;
                col = [60.0 * g, 110.0 * g, 50.0 * g];
            }
        }
        col
    }
}

/// An object present in a frame: base point, camera-facing plane normal `n` and lateral
/// `lat`, half width, height and colour.
struct Live {
    idx: usize,
    p: [f64; 2],
    n: [f64; 2],
    lat: [f64; 2],
    half_w: f64,
    height: f64,
    colour: [f64; 3],
}

/// Whether ground point `g` lies in a cast shadow: its distance to some object's shadow axis
/// segment p → p − L·sun (L = height / tan(elevation); `sun` = (sin, cos) of the azimuth) is
/// at most the object's radius.
fn in_shadow(g: [f64; 2], live: &[Live], sun: (f64, f64), shadow_len: f64) -> bool {
    let (sa, ca) = sun;
    live.iter().any(|o| {
        // Distance from g to the shadow axis segment p → p − L·sun.
        let len = o.height * shadow_len;
        let (ax, ay) = (-ca, -sa);
        let (qx, qy) = (g[0] - o.p[0], g[1] - o.p[1]);
        let along = (qx * ax + qy * ay).clamp(0.0, len);
        let (ex, ey) = (qx - along * ax, qy - along * ay);
        ex * ex + ey * ey <= o.half_w * o.half_w
    })
}

/// Glints: a count of ⌊rate⌋ plus one with probability frac(rate), each a saturated disc of
/// radius 1–2 px at a uniform position, drawn from `rng` (count, then per glint u, v, r).
fn add_glints(rgb: &mut [f64], w: usize, h: usize, rate: f64, rng: &mut impl Rng) {
    let n_glints = {
        let whole = rate.floor() as usize;
        whole + usize::from(rng.random::<f64>() < rate.fract())
    };
    for _ in 0..n_glints {
        let (gu, gv) = (rng.random_range(0..w) as i64, rng.random_range(0..h) as i64);
        let r: i64 = rng.random_range(1..=2);
        for dv in -r..=r {
            for du in -r..=r {
                let (u, v) = (gu + du, gv + dv);
                if du * du + dv * dv <= r * r
                    && u >= 0
                    && v >= 0
                    && (u as usize) < w
                    && (v as usize) < h
                {
                    let i = v as usize * w + u as usize;
                    rgb[i * 3..i * 3 + 3].fill(255.0);
                }
            }
        }
    }
}

/// Per visible object (index, box of the pixels it owns), in `live` order.
fn object_boxes(live: &[Live], owner: &[usize], w: usize) -> Vec<(usize, BoundingBox)> {
    let mut boxes: Vec<(usize, BoundingBox)> = Vec::new();
    for o in live {
        let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
        for (i, _) in owner.iter().enumerate().filter(|(_, ow)| **ow == o.idx) {
            let (u, v) = (i % w, i / w);
            x0 = x0.min(u);
            y0 = y0.min(v);
            x1 = x1.max(u);
            y1 = y1.max(v);
        }
        if x0 != usize::MAX {
            boxes.push((
                o.idx,
                BoundingBox {
                    left: x0 as f64,
                    top: y0 as f64,
                    width: (x1 - x0 + 1) as f64,
                    height: (y1 - y0 + 1) as f64,
                },
            ));
        }
    }
    boxes
}
