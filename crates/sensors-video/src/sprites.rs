//! People-like sprites on a cluttered background, for image-based local detectors: each
//! person is drawn inside a given box as a head, a striped or plain shirt and two legs that
//! swing as it walks, in clothing colours drawn per identity; people are painted far to near
//! (by the bottom of their box), so nearer people hide those behind them; boxes may leave the
//! image. The background (textured ground, coloured blocks, poles) is fixed per renderer, and
//! each frame adds uniform sensor noise.
//!
//! The renderer draws the boxes it is given; where people walk (and who hides whom) is the
//! caller's truth. It is separate from [`crate::render`], whose output it does not change.

use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};
use tracker_model::{BoundingBox, ensure_in_range, ensure_non_negative};

use crate::error::{Error, Result};
use crate::frame::{PixelFormat, VideoFrame};

/// Settings of a [`SpriteRenderer`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpriteConfig {
    /// Frame width in pixels.
    pub width: usize,
    /// Frame height in pixels.
    pub height: usize,
    /// Coloured blocks in the background.
    pub clutter_blocks: usize,
    /// Vertical poles in the background (they look like people's edges to a gradient
    /// detector).
    pub poles: usize,
    /// Half-width of the uniform per-pixel noise, grey levels.
    pub noise: f64,
}

impl Default for SpriteConfig {
    /// 320 × 240 with 60 blocks, 6 poles and ±6 levels of noise.
    fn default() -> Self {
        Self {
            width: 320,
            height: 240,
            clutter_blocks: 60,
            poles: 6,
            noise: 6.0,
        }
    }
}

impl SpriteConfig {
    /// Checks every field.
    pub fn check(&self) -> Result<()> {
        if self.width < 16 || self.height < 16 {
            return Err(Error::ZeroSize {
                width: self.width,
                height: self.height,
            });
        }
        ensure_non_negative(self.noise, "noise")?;
        ensure_in_range(self.noise, 0.0, 128.0, "noise")?;
        Ok(())
    }
}

/// The look of one person.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Appearance {
    /// Skin.
    pub skin: [u8; 3],
    /// Hair.
    pub hair: [u8; 3],
    /// Shirt.
    pub shirt: [u8; 3],
    /// Second shirt colour (stripes), equal to `shirt` for a plain one.
    pub stripes: [u8; 3],
    /// Stripe period as a fraction of the box height (0 for plain).
    pub stripe_period_permille: u16,
    /// Trousers.
    pub trousers: [u8; 3],
}

impl Appearance {
    /// The look of person `id` under renderer seed `seed` (the same for every frame).
    pub fn of(seed: u64, id: u64) -> Self {
        // SplitMix64 over (seed, id): a fixed look per identity without a generator.
        let mut state = seed ^ id.wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let mut next = move || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        };
        let mut colour = |lo: u8, hi: u8| -> [u8; 3] {
            let span = u64::from(hi - lo) + 1;
            [0, 1, 2].map(|_| lo + (next() % span) as u8)
        };
        let shirt = colour(20, 240);
        let striped = shirt[0] % 2 == 0;
        let stripes = if striped { colour(20, 240) } else { shirt };
        let tone = colour(0, 60);
        Self {
            skin: [
                170u8.saturating_add(tone[0]),
                120u8.saturating_add(tone[1]),
                90u8.saturating_add(tone[2] / 2),
            ],
            hair: colour(10, 90),
            shirt,
            stripes,
            stripe_period_permille: if striped {
                40 + u16::from(shirt[1] % 60)
            } else {
                0
            },
            trousers: colour(15, 160),
        }
    }
}

/// Draws people-like sprites over a fixed cluttered background.
#[derive(Debug, Clone)]
pub struct SpriteRenderer {
    config: SpriteConfig,
    background: Vec<u8>,
    seed: u64,
}

impl SpriteRenderer {
    /// A renderer; the background and the appearance seed are drawn from `rng`.
    pub fn new(config: SpriteConfig, rng: &mut impl Rng) -> Result<Self> {
        config.check()?;
        let (w, h) = (config.width, config.height);
        let mut bg = vec![0u8; w * h * 3];
        // Ground: a brownish-grey texture, lighter towards the bottom.
        for y in 0..h {
            for x in 0..w {
                let base = 90.0 + 50.0 * y as f64 / h as f64 + rng.random_range(-12.0..12.0);
                let i = (y * w + x) * 3;
                bg[i] = (base + 8.0).clamp(0.0, 255.0) as u8;
                bg[i + 1] = base.clamp(0.0, 255.0) as u8;
                bg[i + 2] = (base - 10.0).clamp(0.0, 255.0) as u8;
            }
        }
        let mut fill = |x0: usize, y0: usize, x1: usize, y1: usize, c: [u8; 3]| {
            for y in y0..y1.min(h) {
                for x in x0..x1.min(w) {
                    bg[(y * w + x) * 3..][..3].copy_from_slice(&c);
                }
            }
        };
        for _ in 0..config.clutter_blocks {
            let (x0, y0) = (rng.random_range(0..w), rng.random_range(0..h));
            let (bw, bh) = (
                rng.random_range(3..w / 8 + 4),
                rng.random_range(3..h / 8 + 4),
            );
            let c = [rng.random(), rng.random(), rng.random()];
            fill(x0, y0, x0 + bw, y0 + bh, c);
        }
        for _ in 0..config.poles {
            let x0 = rng.random_range(0..w);
            let pw = rng.random_range(2..6);
            let y0 = rng.random_range(0..h / 2);
            let c = [rng.random_range(20..80); 3];
            fill(x0, y0, x0 + pw, h, c);
        }
        Ok(Self {
            config,
            background: bg,
            seed: rng.random(),
        })
    }

    /// The settings.
    pub fn config(&self) -> &SpriteConfig {
        &self.config
    }

    /// The look of person `id`.
    pub fn appearance(&self, id: u64) -> Appearance {
        Appearance::of(self.seed, id)
    }

    /// Frame `frame` with `people` (identity, box) drawn far to near, plus noise from `rng`.
    pub fn render(
        &self,
        frame: u32,
        people: &[(u64, BoundingBox)],
        rng: &mut impl Rng,
    ) -> Result<VideoFrame> {
        let (w, h) = (self.config.width, self.config.height);
        let mut px = self.background.clone();
        let mut order: Vec<&(u64, BoundingBox)> = people.iter().collect();
        order.sort_by(|a, b| a.1.bottom().total_cmp(&b.1.bottom()).then(a.0.cmp(&b.0)));
        for (id, b) in order {
            self.draw(&mut px, w, h, frame, *id, b);
        }
        let n = self.config.noise;
        if n > 0.0 {
            for v in &mut px {
                *v = (f64::from(*v) + rng.random_range(-n..=n))
                    .round()
                    .clamp(0.0, 255.0) as u8;
            }
        }
        VideoFrame::new(w, h, PixelFormat::Rgb, px)
    }

    fn draw(&self, px: &mut [u8], w: usize, h: usize, frame: u32, id: u64, b: &BoundingBox) {
        let look = self.appearance(id);
        // Leg swing: ±15 % of the width, a stride every ~16 frames, phase per person.
        let phase = f64::from(frame) * 0.4 + (id % 17) as f64;
        let swing = 0.15 * phase.sin();
        let x_lo = b.left.floor().max(0.0) as usize;
        let y_lo = b.top.floor().max(0.0) as usize;
        let x_hi = (b.right().ceil().max(0.0) as usize).min(w);
        let y_hi = (b.bottom().ceil().max(0.0) as usize).min(h);
        for y in y_lo..y_hi {
            let v = (y as f64 + 0.5 - b.top) / b.height;
            for x in x_lo..x_hi {
                let u = (x as f64 + 0.5 - b.left) / b.width;
                let c = if v < 0.17 {
                    // Head: an ellipse, hair on top.
                    let (du, dv) = ((u - 0.5) / 0.22, (v - 0.09) / 0.085);
                    if du * du + dv * dv > 1.0 {
                        continue;
                    }
                    if v < 0.05 { look.hair } else { look.skin }
                } else if v < 0.55 {
                    // Torso, narrower at the shoulders' top corners.
                    if (u - 0.5).abs() > 0.5 - 0.2 * (0.25 - v).max(0.0) * 4.0 {
                        continue;
                    }
                    if look.stripe_period_permille > 0
                        && ((v * 1000.0) as u32 / u32::from(look.stripe_period_permille)) % 2 == 1
                    {
                        look.stripes
                    } else {
                        look.shirt
                    }
                } else {
                    // Two legs, each 30 % of the width, swinging in opposite directions.
                    let t = (v - 0.55) / 0.45;
                    let left = 0.3 - swing * t;
                    let right = 0.7 + swing * t;
                    if (u - left).abs() > 0.15 && (u - right).abs() > 0.15 {
                        continue;
                    }
                    look.trousers
                };
                px[(y * w + x) * 3..][..3].copy_from_slice(&c);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    fn renderer(noise: f64) -> SpriteRenderer {
        let config = SpriteConfig {
            noise,
            ..SpriteConfig::default()
        };
        SpriteRenderer::new(config, &mut ChaCha8Rng::seed_from_u64(1)).unwrap()
    }

    #[test]
    fn nearer_people_hide_farther_ones_and_boxes_may_leave_the_image() {
        let r = renderer(0.0);
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let far = BoundingBox::new(100.0, 50.0, 30.0, 80.0).unwrap();
        let near = BoundingBox::new(105.0, 60.0, 30.0, 80.0).unwrap();
        let out = BoundingBox::new(300.0, 100.0, 40.0, 90.0).unwrap();
        let f = r
            .render(0, &[(2, near), (1, far), (3, out)], &mut rng)
            .unwrap();
        // A torso pixel inside both boxes shows the nearer person's shirt (row 60 + 0.3·80).
        let (x, y) = (120usize, 84usize);
        let look = r.appearance(2);
        let p = f.pixel(x, y);
        assert!(p == look.shirt || p == look.stripes, "{p:?} vs {look:?}");
        // Swapping the order of the list changes nothing: painting goes by the box bottoms.
        let g = r
            .render(0, &[(3, out), (1, far), (2, near)], &mut rng)
            .unwrap();
        assert_eq!(f, g);
        // Without people the frame is the background.
        let empty = r.render(0, &[], &mut rng).unwrap();
        assert_eq!(empty.data(), &r.background[..]);
        assert_ne!(empty, f);
    }

    #[test]
    fn looks_differ_between_people_and_stay_fixed() {
        let r = renderer(6.0);
        assert_eq!(r.appearance(5), r.appearance(5));
        let distinct = (0..20u64)
            .map(|i| r.appearance(i).shirt)
            .collect::<std::collections::BTreeSet<_>>();
        assert!(distinct.len() >= 18);
        let bad = SpriteConfig {
            width: 4,
            ..SpriteConfig::default()
        };
        assert!(SpriteRenderer::new(bad, &mut ChaCha8Rng::seed_from_u64(0)).is_err());
    }
}
