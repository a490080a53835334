//! The colour model: a normalised RGB histogram (8 × 8 × 8 bins by default) and the
//! Bhattacharyya coefficient ρ(p, q) = Σ √(p_i q_i) ∈ [0, 1] between two of them.

/// A normalised RGB histogram with `bins` levels per channel.
#[derive(Debug, Clone, PartialEq)]
pub struct ColourHistogram {
    bins: usize,
    mass: Vec<f32>,
}

impl ColourHistogram {
    /// An empty histogram (all zero) with `bins` levels per channel (1 to 256).
    pub fn empty(bins: usize) -> Self {
        let bins = bins.clamp(1, 256);
        Self {
            bins,
            mass: vec![0.0; bins * bins * bins],
        }
    }

    /// Levels per channel.
    pub fn bins(&self) -> usize {
        self.bins
    }

    /// The bin of an RGB value (each channel in [0, 256)).
    #[inline]
    fn index(&self, r: f32, g: f32, b: f32) -> usize {
        let q = |v: f32| ((v.max(0.0) as usize * self.bins) / 256).min(self.bins - 1);
        (q(r) * self.bins + q(g)) * self.bins + q(b)
    }

    /// Adds one pixel with weight `w`.
    #[inline]
    pub fn add(&mut self, rgb: [f32; 3], w: f32) {
        let i = self.index(rgb[0], rgb[1], rgb[2]);
        self.mass[i] += w;
    }

    /// Scales the masses to sum to one (an empty histogram stays empty).
    pub fn normalise(&mut self) {
        let s: f32 = self.mass.iter().sum();
        if s > 0.0 {
            for m in &mut self.mass {
                *m /= s;
            }
        }
    }

    /// The normalised histogram of the pixels of an interleaved RGB buffer of row length
    /// `width` inside the rectangle [x0, x1) × [y0, y1), every `step`-th pixel on both axes.
    pub fn of_rect(rgb: &[f32], width: usize, rect: [usize; 4], step: usize, bins: usize) -> Self {
        let mut h = Self::empty(bins);
        let [x0, y0, x1, y1] = rect;
        let step = step.max(1);
        for y in (y0..y1).step_by(step) {
            for x in (x0..x1).step_by(step) {
                let i = (y * width + x) * 3;
                if let Some(p) = rgb.get(i..i + 3) {
                    h.add([p[0], p[1], p[2]], 1.0);
                }
            }
        }
        h.normalise();
        h
    }

    /// ρ = Σ √(p_i q_i); 0 if the bin counts differ.
    pub fn bhattacharyya(&self, other: &Self) -> f64 {
        if self.bins != other.bins {
            return 0.0;
        }
        self.mass
            .iter()
            .zip(&other.mass)
            .map(|(&p, &q)| f64::from(p * q).sqrt())
            .sum()
    }

    /// self ← (1 − rate) self + rate · other (a slow update of the target model).
    pub fn blend(&mut self, other: &Self, rate: f32) {
        if self.bins != other.bins {
            return;
        }
        for (a, &b) in self.mass.iter_mut().zip(&other.mass) {
            *a = (1.0 - rate) * *a + rate * b;
        }
    }
}
