# Times Stone Soup's GNN, JPDA, GM-PHD and SMC-PHD on the problems of our criterion benches
# (docs/benchmarks.md, rows `gnn_k50_10_scans`, `smc_phd_frame_10_targets_20_clutter_1000_per_target`
# and `gm_phd_frame_10_targets_20_clutter`). This script installs nothing; make the venv first:
#
#     python3 -m venv /tmp/ss && /tmp/ss/bin/pip install stonesoup      # PyPI stonesoup 1.9.x
#     /tmp/ss/bin/python docs/comparisons/stonesoup_trackers.py [repeats]
#
# Same shape of data, not the same bytes (NumPy's generator, not ChaCha8). Every number printed is
# the median over `repeats` (default 7) timed runs; the machine is shared, so run it a few times.
#
# 1. GNN / JPDA on crates/mcmcda/benches/sampler.rs `gnn_k50_10_scans` (tracker-model's
#    SimulationConfig::default() with births_per_scan = 5: Oh, Russell & Sastry 2009's K = 50 batch
#    scene): region [0, 1000]², 10 scans, Poisson(5) births per scan uniform in the region, speed
#    uniform in [0, 50] with a uniform heading, clipped to 100, p_z = 1e-4, p_d = 0.9, Poisson(1)
#    clutter, constant velocity with Q = G diag(100, 100) Gᵀ (G = [T²/2; T], T = 1), R = 100 I.
#    Both trackers use exactly that model (state [x, ẋ, y, ẏ], 2-D positions), the same χ² gate
#    (13.8 ≈ 99.9 %) and the same log-likelihood-ratio cost: Stone Soup's GNNWith2DAssignment over
#    PDAHypothesiser(p_d = 0.9, clutter density (λ_f + λ_b)/V = 6e-6) maximises the product of
#    p_d N(z; ẑ, S) / λ against 1 − p_d, which is mcmcda's `AssignmentCost::LogLikelihoodRatio`.
#    Where it cannot be like for like: track management. mcmcda's GNN keeps one-measurement
#    tentative tracks in the same assignment, starts velocity from two points within the speed
#    bound (‖Δz‖ ≤ d v̄), confirms 2 of 3 and ends a track after d̄ = 5 missed scans. Here a
#    MultiMeasurementInitiator (its own GNN on leftover detections, min_points = 2, holding tracks
#    deleted after 2 misses: 2 of 3) starts at the measurement with velocity variance 499, chosen
#    so that the first gate's 99.9 % ellipse has radius v̄ = 100 like our speed disc, and an
#    UpdateTimeStepsDeleter(5) ends confirmed tracks after 5 missed scans. Time per scan is the time
#    of the whole 10-scan run (association, updates, initiation, deletion) / 10, as in our bench.
#    JPDA: Stone Soup's plain JPDA enumerates joint hypotheses over *all* tracks
#    (itertools.product); on this scene (up to ≈ 50 targets) that is infeasible, so the script
#    counts the joint hypotheses of each scan and stops plain JPDA when a scan has more than
#    JPDA_MAX joint hypotheses; it then times JPDAwithEHM (exact marginals, clustered) instead.
#    mcmcda has no JPDA: the JPDA numbers are context, not a ratio.
#
# 2. GM-PHD / SMC-PHD on crates/phd-filter/benches/phd.rs: 10 people (boxes 40 × 100 at
#    left = 40 + 60 i + 0.5 t, top = 200 + 10 (i mod 3), ±2 px uniform jitter) and 20 clutter boxes
#    uniform in left [0, 600), top [0, 380), every frame; 20 warm-up frames, then one more frame is
#    timed on a copy of the warmed-up filter (copying not timed). PhdConfig::default() with
#    clutter_rate = 20: p_S = 0.99, p_D = 0.95, κ = 20 / (640·480·100·200), births 0.1 per frame
#    spread over the frame's measurements, R = diag(4², 4², 3², 6²) on [c_x, c_y, w, h], random
#    walk with σ = 4 (centre) and 1 (size). Stone Soup handles our 6-D box state
#    [c_x, c_y, w, h, v_x, v_y] directly (LinearGaussianTimeInvariantTransitionModel with F = I,
#    Q = diag(16, 16, 1, 1, 0, 0); LinearGaussian measurement on the first four), so the state and
#    measurement dimensions are like for like. Where it cannot be:
#    - GM-PHD: our newborns (one per measurement, weight ν = 0.1 / |Z|, covariance
#      diag(16, 16, 9, 36, 1, 1)) enter L(z) and are updated in the same frame. Here the same
#      newborn components are added to the mixture, tagged "birth", before Stone Soup's
#      hypothesiser; its PHDUpdater then treats them as ours do (no p_S, no missed-detection
#      copy), except that they are also predicted (+Q), gated against every measurement, and
#      their term in L(z) carries a factor p_D. Stone Soup's estimates are read after the
#      reduction, which includes the updated newborns (ours: before they are added), so it
#      reports more estimates; that is a threshold test, not a cost. Gate: Mahalanobis distance
#      √50 (our χ² = 50); pruning 1e-5, merging at squared Mahalanobis distance 4, at most 100
#      components (our GmConfig).
#    - SMC-PHD: Stone Soup has no measurement-driven birth; the SMCPHDPredictor's birth sampler is
#      given the frame's measurements and draws 200 newborn particles around each (6000 in all,
#      total weight 0.1, as ours), but Stone Soup then evaluates every particle, newborn or not,
#      against every measurement (ours: persistent particles only within the χ² = 50 reach,
#      newborns only against their own measurement) and resamples everything to a fixed count.
#      Particle counts are set to ours: 21,694 particles enter the frame (our bench's count
#      after the warm-up) plus 6000 newborns, resampled back to 21,694. No extraction is timed
#      (ours includes the grouping extraction of eq. 8), so Stone Soup's time is a lower bound.
#      Stone Soup runs on one core (NumPy); ours uses rayon on the machine's 2 threads.
import copy
import datetime
import math
import sys
import time

import numpy as np
import stonesoup
from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
from stonesoup.dataassociator.probability import JPDA, JPDAwithEHM
from stonesoup.deleter.time import UpdateTimeStepsDeleter
from stonesoup.hypothesiser.distance import DistanceHypothesiser
from stonesoup.hypothesiser.gaussianmixture import GaussianMixtureHypothesiser
from stonesoup.hypothesiser.probability import PDAHypothesiser
from stonesoup.initiator.simple import MultiMeasurementInitiator
from stonesoup.measures import Mahalanobis
from stonesoup.mixturereducer.gaussianmixture import GaussianMixtureReducer
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.models.transition.linear import LinearGaussianTimeInvariantTransitionModel
from stonesoup.predictor.kalman import KalmanPredictor
from stonesoup.predictor.particle import SMCPHDPredictor
from stonesoup.resampler.particle import SystematicResampler
from stonesoup.sampler.particle import ParticleSampler
from stonesoup.types.array import StateVectors
from stonesoup.types.detection import Detection, MissedDetection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.multihypothesis import MultipleHypothesis
from stonesoup.types.state import GaussianState, ParticleState, TaggedWeightedGaussianState
from stonesoup.updater.kalman import KalmanUpdater
from stonesoup.updater.particle import SMCPHDUpdater
from stonesoup.updater.pointprocess import PHDUpdater
from stonesoup.updater.probability import PDAUpdater

REPEATS = int(sys.argv[1]) if len(sys.argv) > 1 else 7
T0 = datetime.datetime(2026, 1, 1)
DT = datetime.timedelta(seconds=1)
JPDA_MAX = 200_000  # joint hypotheses in one scan beyond which plain JPDA is not run


def median(xs):
    s = sorted(xs)
    n = len(s)
    return s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2])


# ---------------------------------------------------------------- 1. GNN / JPDA, K = 50 scene
GNN_GATE = 0.999  # χ²₂ quantile 13.8, tracker-model's GATE_CHI2_2D
V, BIRTHS, CLUTTER, P_D, P_Z, N_SCANS = 1e6, 5.0, 1.0, 0.9, 1e-4, 10
SIGMA2_A, R_VAR, SPEED0, VMAX, D_BAR = 100.0, 100.0, 50.0, 100.0, 5

F1 = np.array([[1.0, 1.0], [0.0, 1.0]])
G1 = np.array([[0.5], [1.0]])
Q1 = SIGMA2_A * G1 @ G1.T  # [[25, 50], [50, 100]]: Q = G diag(σ², σ²) Gᵀ per axis
F_CV = np.kron(np.eye(2), F1)  # state [x, ẋ, y, ẏ]
Q_CV = np.kron(np.eye(2), Q1)


def simulate_k50(rng):
    """tracker-model's Simulator::simulate with SimulationConfig::default(), births 5 per scan."""
    alive, scans = [], []
    for k in range(N_SCANS):
        if k > 0:
            survivors = []
            for s in alive:
                if rng.random() < P_Z:
                    continue
                s = F_CV @ s + rng.multivariate_normal(np.zeros(4), Q_CV)
                survivors.append(clip(s))
            alive = survivors
        for _ in range(rng.poisson(BIRTHS)):
            p = rng.uniform(0, 1000, 2)
            speed, heading = SPEED0 * rng.random(), 2 * math.pi * rng.random()
            alive.append(clip(np.array([p[0], speed * math.cos(heading), p[1], speed * math.sin(heading)])))
        zs = [np.array([s[0], s[2]]) + rng.normal(0, math.sqrt(R_VAR), 2) for s in alive if rng.random() < P_D]
        zs += [rng.uniform(0, 1000, 2) for _ in range(rng.poisson(CLUTTER))]
        rng.shuffle(zs)
        scans.append(zs)
    return scans


def clip(s):
    v = math.hypot(s[1], s[3])
    if v > VMAX:
        s[1] *= VMAX / v
        s[3] *= VMAX / v
    return s


cv_model = LinearGaussianTimeInvariantTransitionModel(transition_matrix=F_CV, covariance_matrix=Q_CV)
pos_model = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=R_VAR * np.eye(2))
cv_predictor = KalmanPredictor(cv_model)
cv_updater = KalmanUpdater(pos_model)
# Velocity variance of a newborn: the first predicted innovation covariance is then
# (R + σ_v² + Q₀₀ + R) I ≈ (v̄² / 13.8) I, i.e. the 99.9 % gate is the disc of radius v̄ = 100.
VEL_VAR = VMAX**2 / 13.8155 - 2 * R_VAR - Q1[0, 0]


def pda_hypothesiser():
    return PDAHypothesiser(cv_predictor, cv_updater, clutter_spatial_density=(CLUTTER + BIRTHS) / V,
                           prob_detect=P_D, prob_gate=GNN_GATE)


def initiator():
    return MultiMeasurementInitiator(
        prior_state=GaussianState(np.zeros((4, 1)), np.diag([0.0, VEL_VAR, 0.0, VEL_VAR])),
        measurement_model=pos_model,
        deleter=UpdateTimeStepsDeleter(time_steps_since_update=2),  # 2 of 3
        data_associator=GNNWith2DAssignment(pda_hypothesiser()),
        updater=cv_updater,
        min_points=2)


class TooManyJointHypotheses(Exception):
    pass


class CountingJPDA(JPDA):
    """Stone Soup's plain JPDA, refusing scans whose joint-hypothesis product exceeds JPDA_MAX."""

    largest = 0

    @classmethod
    def enumerate_JPDA_hypotheses(cls, tracks, multihypths):
        n = 1
        for track in tracks:
            n *= len(multihypths[track])
        CountingJPDA.largest = max(CountingJPDA.largest, n)
        if n > JPDA_MAX:
            raise TooManyJointHypotheses(n)
        return super().enumerate_JPDA_hypotheses(tracks, multihypths)


def run_tracker(scans, kind):
    if kind == "gnn":
        associator, track_updater = GNNWith2DAssignment(pda_hypothesiser()), cv_updater
    elif kind == "jpda":
        associator, track_updater = CountingJPDA(pda_hypothesiser()), PDAUpdater(pos_model)
    else:
        associator, track_updater = JPDAwithEHM(pda_hypothesiser()), PDAUpdater(pos_model)
    init, deleter, tracks = initiator(), UpdateTimeStepsDeleter(time_steps_since_update=D_BAR), set()
    for k, dets in enumerate(scans):
        t = T0 + k * DT
        hyps = associator.associate(tracks, dets, t)
        used = set()
        for track, hyp in hyps.items():
            if kind == "gnn":
                if hyp:
                    track.append(track_updater.update(hyp))
                    used.add(hyp.measurement)
                else:
                    track.append(hyp.prediction)
            else:
                # PDA update over the gated detections; those inside some gate do not start tracks.
                track.append(track_updater.update(hyp))
                used |= {h.measurement for h in hyp if h}
        tracks -= deleter.delete_tracks(tracks)
        tracks |= init.initiate(dets - used, t)
    return tracks


def to_detections(scans):
    return [{Detection(np.array([[z[0]], [z[1]]]), timestamp=T0 + k * DT, measurement_model=pos_model)
             for z in zs} for k, zs in enumerate(scans)]


def time_runs(f, repeats=REPEATS):
    ts = []
    for _ in range(repeats):
        t = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t)
    return median(ts), min(ts)


# ---------------------------------------------------------------- 2. PHD scene
P_S, P_D_PHD, CLUTTER_PHD, BIRTH_RATE = 0.99, 0.95, 20.0, 0.1
VOLUME = 640.0 * 480.0 * 100.0 * 200.0
KAPPA = CLUTTER_PHD / VOLUME
R_BOX = np.diag([4.0**2, 4.0**2, 3.0**2, 6.0**2])
Q_BOX = np.diag([16.0, 16.0, 1.0, 1.0, 0.0, 0.0])  # random walk: σ 4 (centre), 1 (size); v unused
BIRTH_COV = np.diag([16.0, 16.0, 9.0, 36.0, 1.0, 1.0])  # GmPhd::new with Motion::RandomWalk
PERSISTENT, BIRTH_PER_Z = 21_694, 200  # our bench's particle count after warm-up; J_b


def phd_frames(n, rng):
    """crates/phd-filter/benches/phd.rs `frames`, as [c_x, c_y, w, h] measurements."""
    people = [(40.0 + 60.0 * i, 200.0 + 10.0 * (i % 3)) for i in range(10)]
    out = []
    for t in range(n):
        boxes = [(x + 0.5 * t + rng.uniform(-2, 2), y + rng.uniform(-2, 2)) for x, y in people]
        boxes += [(rng.uniform(0, 600), rng.uniform(0, 380)) for _ in range(20)]
        out.append([np.array([l + 20.0, tp + 50.0, 40.0, 100.0]) for l, tp in boxes])
    return out


box_model = LinearGaussianTimeInvariantTransitionModel(transition_matrix=np.eye(6), covariance_matrix=Q_BOX)
box_meas = LinearGaussian(ndim_state=6, mapping=(0, 1, 2, 3), noise_covar=R_BOX)


def box_detections(zs, t):
    return {Detection(z.reshape(4, 1), timestamp=t, measurement_model=box_meas) for z in zs}


# GM-PHD
gm_predictor = KalmanPredictor(box_model)
gm_kalman = KalmanUpdater(box_meas)
gm_hypothesiser = GaussianMixtureHypothesiser(
    DistanceHypothesiser(gm_predictor, gm_kalman, Mahalanobis(), missed_distance=math.sqrt(50.0)),
    order_by_detection=True)
gm_updater = PHDUpdater(gm_kalman, clutter_spatial_density=KAPPA, prob_detection=P_D_PHD, prob_survival=P_S)
gm_reducer = GaussianMixtureReducer(prune_threshold=1e-5, pruning=True, merge_threshold=4.0, merging=True,
                                    max_number_components=100)


def gm_step(components, zs, k):
    t, prev = T0 + k * DT, T0 + (k - 1) * DT
    nu = BIRTH_RATE / len(zs)
    newborn = [TaggedWeightedGaussianState(np.concatenate([z, [0.0, 0.0]]).reshape(6, 1), BIRTH_COV,
                                           weight=nu, tag="birth", timestamp=prev) for z in zs]
    hyps = gm_hypothesiser.hypothesise(list(components) + newborn, box_detections(zs, t), timestamp=t,
                                       order_by_detection=True)
    reduced = list(gm_reducer.reduce(gm_updater.update(hyps)))
    estimates = [c for c in reduced if c.weight > 0.5]
    return reduced, estimates


# SMC-PHD
class BirthAround:
    """A birth density for SMCPHDPredictor: J_b particles around each of the frame's measurements."""

    def __init__(self, rng):
        self.rng, self.zs = rng, []

    def __call__(self, num_samples):
        per = num_samples // len(self.zs)
        assert per * len(self.zs) == num_samples
        zs = np.repeat(np.array(self.zs), per, axis=0)
        x = np.zeros((num_samples, 6))
        x[:, :4] = zs + self.rng.standard_normal((num_samples, 4)) * np.sqrt(np.diag(R_BOX))
        x[:, 4:] = self.rng.standard_normal((num_samples, 2))
        return x.T


def smc_filter(rng):
    birth = BirthAround(rng)
    sampler = ParticleSampler(distribution_func=birth, params={"num_samples": 1}, ndim_state=6)
    predictor = SMCPHDPredictor(box_model, death_probability=-math.log(P_S), birth_probability=0.0,
                                birth_rate=BIRTH_RATE, birth_sampler=sampler)
    updater = SMCPHDUpdater(measurement_model=box_meas, prob_detect=P_D_PHD, clutter_intensity=KAPPA,
                            resampler=SystematicResampler(), num_samples=PERSISTENT)
    return birth, predictor, updater


def smc_step(birth, predictor, updater, prior, zs, k, rs):
    t = T0 + k * DT
    birth.zs = zs
    n_birth = BIRTH_PER_Z * len(zs)
    predictor.birth_probability = n_birth / len(prior)  # num_birth = round(P_b N) = J_b |Z|
    prediction = predictor.predict(prior, timestamp=t, random_state=rs)
    dets = box_detections(zs, t)
    hyps = MultipleHypothesis([SingleHypothesis(prediction, MissedDetection(timestamp=t))]
                              + [SingleHypothesis(prediction, d) for d in dets])
    return updater.update(hyps), len(prediction)


def main():
    print("stonesoup %s, numpy %s, python %s" % (stonesoup.__version__, np.__version__, sys.version.split()[0]))
    print("each time: median of %d runs (best in brackets)" % REPEATS)

    scans = simulate_k50(np.random.default_rng(50))
    dets = to_detections(scans)
    print("K = 50 scene: %d measurements over %d scans (%s per scan)"
          % (sum(map(len, scans)), N_SCANS, [len(s) for s in scans]))
    med, best = time_runs(lambda: run_tracker(dets, "gnn"))
    print("GNN (GNNWith2DAssignment + PDAHypothesiser), 10 scans: %.1f ms, per scan %.2f ms (best %.2f)"
          % (med * 1e3, med * 1e2, best * 1e2))
    print("  confirmed tracks at the end: %d" % len(run_tracker(dets, "gnn")))
    try:
        med, best = time_runs(lambda: run_tracker(dets, "jpda"))
        print("JPDA (plain, PDAHypothesiser), per scan %.2f ms (best %.2f); largest scan: %d joint hypotheses"
              % (med * 1e2, best * 1e2, CountingJPDA.largest))
    except TooManyJointHypotheses as e:
        print("JPDA (plain, PDAHypothesiser): infeasible on this scene, a scan has %d joint hypotheses "
              "(itertools.product over all tracks; stopped above %d)" % (e.args[0], JPDA_MAX))
    med, best = time_runs(lambda: run_tracker(dets, "ehm"))
    print("JPDAwithEHM (exact JPDA marginals, PDAHypothesiser), per scan %.2f ms (best %.2f)"
          % (med * 1e2, best * 1e2))

    frames = phd_frames(21, np.random.default_rng(7))
    components = []
    for k, zs in enumerate(frames[:20]):
        components, _ = gm_step(components, zs, k)
    ts, n_est = [], 0
    for _ in range(REPEATS):
        state = copy.deepcopy(components)
        t = time.perf_counter()
        _, est = gm_step(state, frames[20], 20)
        ts.append(time.perf_counter() - t)
        n_est = len(est)
    print("GM-PHD (6-D box state), one frame of 10 targets + 20 clutter after 20 warm-up frames: "
          "%.1f ms (best %.1f); %d components in, %d estimates"
          % (median(ts) * 1e3, min(ts) * 1e3, len(components), n_est))

    rs = np.random.RandomState(1)
    birth, predictor, updater = smc_filter(np.random.default_rng(2))
    # Start with PERSISTENT particles spread over the image (total weight 1), then warm up.
    x = np.zeros((6, PERSISTENT))
    x[0] = rs.uniform(0, 640, PERSISTENT)
    x[1] = rs.uniform(0, 480, PERSISTENT)
    x[2], x[3] = 40.0, 100.0
    state = ParticleState(StateVectors(x), log_weight=np.full(PERSISTENT, -math.log(PERSISTENT)),
                          timestamp=T0 - DT)
    for k, zs in enumerate(frames[:20]):
        state, _ = smc_step(birth, predictor, updater, state, zs, k, rs)
    ts = []
    for _ in range(REPEATS):
        prior = copy.deepcopy(state)
        t = time.perf_counter()
        post, n = smc_step(birth, predictor, updater, prior, frames[20], 20, rs)
        ts.append(time.perf_counter() - t)
    print("SMC-PHD (6-D box state), same frame: %.1f ms (best %.1f); %d particles predicted and updated "
          "against %d measurements, resampled to %d; N̂ = %.1f"
          % (median(ts) * 1e3, min(ts) * 1e3, n, len(frames[20]), len(post),
             float(np.exp(np.logaddexp.reduce(post.log_weight)))))


if __name__ == "__main__":
    main()
