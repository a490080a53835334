//! Output boxes that follow a track's detections (`[boxes]`).

use super::*;

/// A track's (frame, box) pairs from its measurement ids (indices into `detections`, which
/// `problem_of` orders by id).
pub(super) fn detection_boxes(
    detections: &Detections,
    meas: &[MeasId],
) -> Vec<(Frame, BoundingBox)> {
    meas.iter()
        .map(|&m| {
            let d = detections.of(m);
            (d.frame, d.bbox)
        })
        .collect()
}

/// Frames on either side whose detections the box kernel of width σ reads: 3σ, rounded up
/// (saturating, so a huge σ reads the whole track instead of overflowing).
pub(super) fn kernel_reach(sigma: f64) -> i64 {
    (3.0 * sigma).ceil() as i64
}

/// Boxes of a track from its detections `dets` (frame, box; frames strictly increasing): at
/// every frame from the first detection to the last (or to `until`, when given: the fit then
/// uses only the detections up to it and outputs that one frame), each edge is a local-linear
/// fit with Gaussian kernel weights of σ = `smoothing_frames` over the detections within 3σ;
/// where fewer than two distinct frames are in reach, the edges are interpolated linearly
/// between the nearest detections. `extrapolate_frames` frames are added at both ends.
pub fn smooth_boxes(
    dets: &[(Frame, BoundingBox)],
    config: &BoxConfig,
    until: Option<Frame>,
) -> Result<Vec<TrackPoint>> {
    let dets: Vec<(Frame, BoundingBox)> = match until {
        Some(u) => dets.iter().copied().filter(|d| d.0 <= u).collect(),
        None => dets.to_vec(),
    };
    let (Some(&(f0, _)), Some(&(f1, _))) = (dets.first(), dets.last()) else {
        return Ok(Vec::new());
    };
    let sigma = config.smoothing_frames;
    let reach = kernel_reach(sigma);
    let e = i64::from(config.extrapolate_frames);
    let frames: Vec<i64> = match until {
        Some(u) => vec![i64::from(u)],
        None => {
            ((i64::from(f0) - e).max(0)..=(i64::from(f1) + e).min(i64::from(Frame::MAX))).collect()
        }
    };
    let edges = |b: &BoundingBox| [b.left, b.top, b.right(), b.bottom()];
    let mut out = Vec::with_capacity(frames.len());
    let mut lo = 0usize;
    for f in frames {
        while lo < dets.len() && i64::from(dets[lo].0) < f.saturating_sub(reach) {
            lo += 1;
        }
        // Weighted sums for the local-linear fit of each edge: Σw, Σw·x, Σw·x², Σw·y, Σw·x·y.
        let (mut sw, mut sx, mut sxx) = (0.0, 0.0, 0.0);
        let (mut sy, mut sxy) = ([0.0f64; 4], [0.0f64; 4]);
        let mut n = 0usize;
        for &(g, b) in dets[lo..]
            .iter()
            .take_while(|d| i64::from(d.0) <= f.saturating_add(reach))
        {
            let x = (i64::from(g) - f) as f64;
            let w = (-0.5 * (x / sigma).powi(2)).exp();
            let y = edges(&b);
            sw += w;
            sx += w * x;
            sxx += w * x * x;
            for k in 0..4 {
                sy[k] += w * y[k];
                sxy[k] += w * x * y[k];
            }
            n += 1;
        }
        let det = sw * sxx - sx * sx;
        let e4: [f64; 4] = if n >= 2 && det > 1e-9 * sw * sw {
            // The fit's value at x = 0.
            std::array::from_fn(|k| (sxx * sy[k] - sx * sxy[k]) / det)
        } else {
            // Linear interpolation between the nearest detections (constant beyond the ends).
            let after = dets.partition_point(|d| i64::from(d.0) < f);
            let (a, b) = match (after.checked_sub(1).map(|i| dets[i]), dets.get(after)) {
                (Some(a), Some(b)) => (a, *b),
                (Some(a), None) => (a, a),
                (None, Some(b)) => (*b, *b),
                (None, None) => continue,
            };
            let (ya, yb) = (edges(&a.1), edges(&b.1));
            let span = f64::from(b.0) - f64::from(a.0);
            let t = if span > 0.0 {
                ((f - i64::from(a.0)) as f64 / span).clamp(0.0, 1.0)
            } else {
                0.0
            };
            std::array::from_fn(|k| ya[k] + t * (yb[k] - ya[k]))
        };
        let (w, h) = ((e4[2] - e4[0]).max(1.0), (e4[3] - e4[1]).max(1.0));
        // f is within [0, Frame::MAX] by construction.
        let frame = crate::error::frame_of(f)?;
        out.push(TrackPoint::boxed(
            frame,
            BoundingBox::new(e4[0], e4[1], w, h)?,
        ));
    }
    Ok(out)
}
