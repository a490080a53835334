//! The six approaches of Kushwaha et al. (MFI 2008, Figs. 10–11): audio, video and
//! audio+video, each fused by the weighted sum or by the floored product, and [`PerApproach`],
//! one value for each of them.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::Modalities;

/// One of the six approaches, modality × fusion rule, in the order of the report's columns
/// ([`Approach::ALL`]): the weighted sum's three, then the product's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Approach {
    /// Audio, weighted sum.
    AudioSum,
    /// Video, weighted sum.
    VideoSum,
    /// Audio+video, weighted sum.
    AudioVideoSum,
    /// Audio, floored product.
    AudioProduct,
    /// Video, floored product.
    VideoProduct,
    /// Audio+video, floored product.
    AudioVideoProduct,
}

impl Approach {
    /// The six approaches in report order: audio, video, audio+video under the weighted sum,
    /// then the same under the floored product.
    pub const ALL: [Approach; 6] = [
        Approach::AudioSum,
        Approach::VideoSum,
        Approach::AudioVideoSum,
        Approach::AudioProduct,
        Approach::VideoProduct,
        Approach::AudioVideoProduct,
    ];

    /// The approach that fuses `modalities` by the floored product (`product`) or the
    /// weighted sum.
    pub const fn new(modalities: Modalities, product: bool) -> Approach {
        match (modalities, product) {
            (Modalities::Audio, false) => Approach::AudioSum,
            (Modalities::Video, false) => Approach::VideoSum,
            (Modalities::Both, false) => Approach::AudioVideoSum,
            (Modalities::Audio, true) => Approach::AudioProduct,
            (Modalities::Video, true) => Approach::VideoProduct,
            (Modalities::Both, true) => Approach::AudioVideoProduct,
        }
    }

    /// The name in reports and metric names: `audio, sum`, ..., `audio+video, product`.
    pub const fn name(self) -> &'static str {
        match self {
            Approach::AudioSum => "audio, sum",
            Approach::VideoSum => "video, sum",
            Approach::AudioVideoSum => "audio+video, sum",
            Approach::AudioProduct => "audio, product",
            Approach::VideoProduct => "video, product",
            Approach::AudioVideoProduct => "audio+video, product",
        }
    }

    /// The key of its settings ([`PerApproach`]'s field) and of
    /// [`Params::multi_peak_scores`](super::Params::multi_peak_scores): `audio_sum`, ...,
    /// `audio_video_product` (the fields of [`PerApproach`]).
    pub const fn settings_key(self) -> &'static str {
        match self {
            Approach::AudioSum => "audio_sum",
            Approach::VideoSum => "video_sum",
            Approach::AudioVideoSum => "audio_video_sum",
            Approach::AudioProduct => "audio_product",
            Approach::VideoProduct => "video_product",
            Approach::AudioVideoProduct => "audio_video_product",
        }
    }

    /// The sensors it fuses.
    pub const fn modalities(self) -> Modalities {
        match self {
            Approach::AudioSum | Approach::AudioProduct => Modalities::Audio,
            Approach::VideoSum | Approach::VideoProduct => Modalities::Video,
            Approach::AudioVideoSum | Approach::AudioVideoProduct => Modalities::Both,
        }
    }

    /// Whether it fuses by the floored product (false: the weighted sum).
    pub const fn is_product(self) -> bool {
        matches!(
            self,
            Approach::AudioProduct | Approach::VideoProduct | Approach::AudioVideoProduct
        )
    }

    /// Its position in [`Approach::ALL`] (the report's column and chart order).
    pub const fn index(self) -> usize {
        self as usize
    }

    /// The approach at position `i` of [`Approach::ALL`], if any.
    pub fn from_index(i: usize) -> Option<Approach> {
        Approach::ALL.get(i).copied()
    }

    /// The approach whose [`settings_key`](Approach::settings_key) is `key`, if any.
    pub fn from_settings_key(key: &str) -> Option<Approach> {
        Approach::ALL.into_iter().find(|a| a.settings_key() == key)
    }
}

impl fmt::Display for Approach {
    /// The approach's [`name`](Approach::name).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One value per approach, each a field named by the approach's
/// [`settings_key`](Approach::settings_key) (so that a settings table deserialises
/// into one; unknown fields are rejected).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PerApproach<T> {
    /// Audio, weighted sum.
    pub audio_sum: T,
    /// Video, weighted sum.
    pub video_sum: T,
    /// Audio+video, weighted sum.
    pub audio_video_sum: T,
    /// Audio, floored product.
    pub audio_product: T,
    /// Video, floored product.
    pub video_product: T,
    /// Audio+video, floored product.
    pub audio_video_product: T,
}

impl<T> PerApproach<T> {
    /// Each approach's value `f(approach)`, called in [`Approach::ALL`] order.
    pub fn from_fn(mut f: impl FnMut(Approach) -> T) -> Self {
        PerApproach {
            audio_sum: f(Approach::AudioSum),
            video_sum: f(Approach::VideoSum),
            audio_video_sum: f(Approach::AudioVideoSum),
            audio_product: f(Approach::AudioProduct),
            video_product: f(Approach::VideoProduct),
            audio_video_product: f(Approach::AudioVideoProduct),
        }
    }

    /// As [`from_fn`](PerApproach::from_fn), stopping at the first error.
    pub fn try_from_fn<E>(mut f: impl FnMut(Approach) -> Result<T, E>) -> Result<Self, E> {
        Ok(PerApproach {
            audio_sum: f(Approach::AudioSum)?,
            video_sum: f(Approach::VideoSum)?,
            audio_video_sum: f(Approach::AudioVideoSum)?,
            audio_product: f(Approach::AudioProduct)?,
            video_product: f(Approach::VideoProduct)?,
            audio_video_product: f(Approach::AudioVideoProduct)?,
        })
    }

    /// Approach `a`'s value.
    pub fn get(&self, a: Approach) -> &T {
        match a {
            Approach::AudioSum => &self.audio_sum,
            Approach::VideoSum => &self.video_sum,
            Approach::AudioVideoSum => &self.audio_video_sum,
            Approach::AudioProduct => &self.audio_product,
            Approach::VideoProduct => &self.video_product,
            Approach::AudioVideoProduct => &self.audio_video_product,
        }
    }

    /// Approach `a`'s value, to change.
    pub fn get_mut(&mut self, a: Approach) -> &mut T {
        match a {
            Approach::AudioSum => &mut self.audio_sum,
            Approach::VideoSum => &mut self.video_sum,
            Approach::AudioVideoSum => &mut self.audio_video_sum,
            Approach::AudioProduct => &mut self.audio_product,
            Approach::VideoProduct => &mut self.video_product,
            Approach::AudioVideoProduct => &mut self.audio_video_product,
        }
    }

    /// Each approach with its value, in [`Approach::ALL`] order.
    pub fn iter(&self) -> impl Iterator<Item = (Approach, &T)> {
        Approach::ALL.into_iter().map(|a| (a, self.get(a)))
    }

    /// Each approach's value mapped by `f(approach, value)`.
    pub fn map<U>(&self, mut f: impl FnMut(Approach, &T) -> U) -> PerApproach<U> {
        PerApproach::from_fn(|a| f(a, self.get(a)))
    }
}
