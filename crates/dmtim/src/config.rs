//! Sensors and the settings of a DMTIM run, checked once.

use identity_mgmt::{FromSamplesConfig, FusionConfig, NotScalableRule, ScalingConfig};
use mcmcda::{McmcdaConfig, OnlineConfig};
use serde::{Deserialize, Serialize};
use tracker_model::{GATE_CHI2_2D, Vec2, ensure_in_range, ensure_positive};

use crate::error::{Result, invalid};

/// One sensor: a centre and a circular sensing range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSpec {
    /// Name for reports (e.g. "ATC7").
    pub name: String,
    /// Centre of the sensing disc.
    pub centre: [f64; 2],
    /// Radius of the sensing disc.
    pub range_m: f64,
}

impl SensorSpec {
    /// The centre as a vector.
    pub fn centre(&self) -> Vec2 {
        Vec2::new(self.centre[0], self.centre[1])
    }

    /// Whether `p` is inside the range.
    pub fn covers(&self, p: Vec2) -> bool {
        (p - self.centre()).norm() <= self.range_m
    }

    /// Whether two sensors' ranges overlap (they are neighbours and exchange queries).
    pub fn overlaps(&self, other: &SensorSpec) -> bool {
        (self.centre() - other.centre()).norm() < self.range_m + other.range_m
    }
}

/// How each sensor turns tracks into identities.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum IdentityMode {
    /// Belief matrices mixed from MCMCDA samples where tracks come close (Oh, Hwang &
    /// Sastry 2008).
    #[default]
    Beliefs,
    /// The baseline: every frame, each identity moves to the nearest track estimate from
    /// where its track was in the previous frame (optimal assignment on distance, gated);
    /// no MCMC labels and no mixing.
    NearestTrack,
}

/// What column a read puts into the belief matrix before rescaling.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReadUpdate {
    /// The track's current column times the read's likelihood, normalised (Bayes' rule; a
    /// read can only sharpen what the sensor believed, unless it contradicts it entirely,
    /// in which case the likelihood itself is used).
    #[default]
    Posterior,
    /// The read's likelihood alone, as the papers' "replace the column" (a read with an error
    /// rate can then make a certain column less certain).
    Replace,
}

/// Local information: transponder reads or visual identifications at some sensors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LocalInfoConfig {
    /// Indices of the sensors that can read identities.
    pub sensors: Vec<usize>,
    /// Probability that a target inside such a sensor's range is read in a frame.
    pub probability: f64,
    /// Probability that a read names a wrong identity (uniform over the others). The sensor
    /// knows this rate: a read of identity i becomes the information vector
    /// l = (1 − e) at i and e/(n − 1) elsewhere.
    pub error_rate: f64,
    /// Only frames in this half-open range produce reads (`None`: all frames).
    pub frames: Option<[u64; 2]>,
}

impl Default for LocalInfoConfig {
    fn default() -> Self {
        Self {
            sensors: Vec::new(),
            probability: 0.0,
            error_rate: 0.0,
            frames: None,
        }
    }
}

/// What the simulated sensors observe.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensingConfig {
    /// Detection probability of a target inside the range.
    pub p_detect: f64,
    /// Expected false alarms per scan in each sensor's disc (Poisson).
    pub clutter_per_scan: f64,
    /// Standard deviation of each position coordinate.
    pub noise_std_m: f64,
}

impl Default for SensingConfig {
    fn default() -> Self {
        Self {
            p_detect: 0.9,
            clutter_per_scan: 1.0,
            noise_std_m: 0.3,
        }
    }
}

/// Every setting of a run. Choices the papers leave open are fields (defaults in
/// `docs/identity.md`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DmtimConfig {
    /// The sensors.
    pub sensors: Vec<SensorSpec>,
    /// What they observe.
    pub sensing: SensingConfig,
    /// The MCMCDA model of every sensor; its `volume` is replaced by each sensor's disc area.
    pub mcmcda: McmcdaConfig,
    /// The sliding window.
    pub online: OnlineConfig,
    /// Two track estimates closer than this are interacting; their identities mix when they
    /// separate.
    pub interaction_distance_m: f64,
    /// MCMC samples drawn for one mixing matrix.
    pub join_samples: u64,
    /// From samples to a doubly stochastic mixing matrix.
    pub mixing: FromSamplesConfig,
    /// Rescaling after local information and fusion (default: soften a contradicting
    /// column with weight 0.5 on the old one, since reads can be wrong).
    pub scaling: ScalingConfig,
    /// Belief fusion with neighbours; `None` exchanges no beliefs (hand-overs still happen).
    pub fusion: Option<FusionConfig>,
    /// Neighbours are queried every this many frames.
    pub exchange_every: u64,
    /// χ² gate of track-to-track association (Mahalanobis distance between two position
    /// estimates with covariance 2R).
    pub merge_gate_chi2: f64,
    /// A track that ends within this distance of its range's edge is handed over.
    pub handover_margin_m: f64,
    /// A hand-over waits this many frames for the receiver to start a matching track.
    pub handover_ttl_frames: u64,
    /// Local information.
    pub local_info: LocalInfoConfig,
    /// The column a read contributes.
    pub read_update: ReadUpdate,
    /// ε of the "doubt" step applied when a read contradicts a certain belief
    /// (`ReadRule::AfterDoubt`).
    pub read_doubt: f64,
    /// Beliefs or the nearest-track baseline.
    pub identity_mode: IdentityMode,
}

impl Default for DmtimConfig {
    fn default() -> Self {
        Self {
            sensors: Vec::new(),
            sensing: SensingConfig::default(),
            mcmcda: McmcdaConfig::default(),
            online: OnlineConfig {
                window: 10,
                samples_per_scan: 300,
                ..OnlineConfig::default()
            },
            interaction_distance_m: 3.0,
            join_samples: 300,
            mixing: FromSamplesConfig::default(),
            scaling: ScalingConfig {
                not_scalable: NotScalableRule::Soften { old_weight: 0.5 },
                ..ScalingConfig::default()
            },
            fusion: Some(FusionConfig::default()),
            exchange_every: 1,
            merge_gate_chi2: GATE_CHI2_2D,
            handover_margin_m: 3.0,
            handover_ttl_frames: 5,
            local_info: LocalInfoConfig::default(),
            read_doubt: 0.1,
            read_update: ReadUpdate::Posterior,
            identity_mode: IdentityMode::Beliefs,
        }
    }
}

impl DmtimConfig {
    /// Checks every field (the MCMCDA model is checked per sensor when a run starts). The
    /// first invalid field is reported, in the order the groups below are checked.
    pub fn check(&self) -> Result<()> {
        self.check_sensors()?;
        self.check_sensing()?;
        self.check_tracking()?;
        self.check_exchange()?;
        self.check_local_info()
    }

    /// At least one sensor, each with a positive range and a finite centre.
    fn check_sensors(&self) -> Result<()> {
        if self.sensors.is_empty() {
            return Err(invalid("sensors", "no sensors".into()));
        }
        for s in &self.sensors {
            ensure_positive(s.range_m, "sensors.range_m")?;
            if !(s.centre[0].is_finite() && s.centre[1].is_finite()) {
                return Err(invalid(
                    "sensors.centre",
                    format!("{:?} is not finite", s.centre),
                ));
            }
        }
        Ok(())
    }

    /// What the simulated sensors observe: a probability, a finite non-negative clutter rate
    /// and a positive noise.
    fn check_sensing(&self) -> Result<()> {
        ensure_in_range(self.sensing.p_detect, 0.0, 1.0, "sensing.p_detect")?;
        if !(self.sensing.clutter_per_scan >= 0.0 && self.sensing.clutter_per_scan.is_finite()) {
            return Err(invalid(
                "sensing.clutter_per_scan",
                format!(
                    "{} is not a finite non-negative rate",
                    self.sensing.clutter_per_scan
                ),
            ));
        }
        ensure_positive(self.sensing.noise_std_m, "sensing.noise_std_m")?;
        Ok(())
    }

    /// The tracking phase: the window, the interaction distance and the mixing samples.
    fn check_tracking(&self) -> Result<()> {
        self.online
            .check()
            .map_err(|e| invalid("online", e.to_string()))?;
        ensure_positive(self.interaction_distance_m, "interaction_distance_m")?;
        if self.join_samples == 0 {
            return Err(invalid("join_samples", "0 samples".into()));
        }
        self.mixing
            .check()
            .map_err(|e| invalid("mixing", e.to_string()))
    }

    /// Rescaling, fusion and what sensors exchange: the query period, the association gate
    /// and the hand-over margin.
    fn check_exchange(&self) -> Result<()> {
        self.scaling
            .check()
            .map_err(|e| invalid("scaling", e.to_string()))?;
        if let Some(f) = &self.fusion {
            f.check().map_err(|e| invalid("fusion", e.to_string()))?;
        }
        if self.exchange_every == 0 {
            return Err(invalid("exchange_every", "0 frames".into()));
        }
        ensure_positive(self.merge_gate_chi2, "merge_gate_chi2")?;
        if !(self.handover_margin_m >= 0.0 && self.handover_margin_m.is_finite()) {
            return Err(invalid(
                "handover_margin_m",
                format!("{} is not finite and non-negative", self.handover_margin_m),
            ));
        }
        Ok(())
    }

    /// Local information: probabilities, the doubt ε in (0, 1], and readers that exist.
    fn check_local_info(&self) -> Result<()> {
        ensure_in_range(
            self.local_info.probability,
            0.0,
            1.0,
            "local_info.probability",
        )?;
        if !(self.read_doubt > 0.0 && self.read_doubt <= 1.0) {
            return Err(invalid(
                "read_doubt",
                format!("{} is not in (0, 1]", self.read_doubt),
            ));
        }
        ensure_in_range(
            self.local_info.error_rate,
            0.0,
            1.0,
            "local_info.error_rate",
        )?;
        if let Some(&bad) = self
            .local_info
            .sensors
            .iter()
            .find(|&&s| s >= self.sensors.len())
        {
            return Err(invalid(
                "local_info.sensors",
                format!(
                    "sensor {bad} does not exist ({} sensors)",
                    self.sensors.len()
                ),
            ));
        }
        Ok(())
    }
}
