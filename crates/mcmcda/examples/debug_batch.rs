use mcmcda::*;
use rand::SeedableRng;
use tracker_model::SimulationConfig;
fn main() {
    let k: f64 = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(10.0);
    let n: u64 = std::env::args()
        .nth(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(50000);
    let sim = SimulationConfig {
        births_per_scan: k / 10.0,
        initial_speed_max: 50.0,
        ..SimulationConfig::default()
    }
    .check()
    .unwrap()
    .simulate(&mut rand_chacha::ChaCha8Rng::seed_from_u64(3))
    .unwrap();
    let model = McmcdaConfig {
        births_per_scan: k / 10.0,
        ..McmcdaConfig::default()
    }
    .check()
    .unwrap();
    let problem = Problem::from_scans(&model, &sim.scans).unwrap();
    let w = 0..=problem.n_scans() - 1;
    let truth = tracks_by_origin(&sim.scans);
    let init = greedy_initial_partition(&model, &problem, w.clone()).unwrap();
    let t = Partition::from_tracks(&model, &problem, w.clone(), &truth);
    println!("init lp {}", init.log_posterior());
    match &t {
        Ok(t) => println!("truth lp {}", t.log_posterior()),
        Err(e) => println!("truth infeasible {e}"),
    }
    let run = run_chains(&init, 1, n, 1).unwrap();
    println!("map lp {} stats {:?}", run.log_posterior, run.stats);
    let gnn = nearest_neighbour_tracks(
        &model,
        &problem,
        w.clone(),
        &NearestNeighbourConfig::default(),
    )
    .unwrap();
    println!(
        "gospa map {:?}",
        gospa_parts(&model, &problem, &sim.truth, &run.tracks)
    );
    println!(
        "gospa gnn {:?}",
        gospa_parts(&model, &problem, &sim.truth, &gnn)
    );
    println!(
        "gospa oracle {:?}",
        gospa_parts(&model, &problem, &sim.truth, &truth)
    );
    let mut truth_sorted = truth.clone();
    truth_sorted.sort();
    let scan = |v: &Vec<u32>| v.iter().map(|&m| problem.scan_of(m)).collect::<Vec<_>>();
    for tr in &truth_sorted {
        if !run.tracks.contains(tr) {
            let owner: Vec<Option<usize>> = tr
                .iter()
                .map(|m| run.tracks.iter().position(|t| t.contains(m)))
                .collect();
            println!(
                "missing truth {:?} scans {:?} map owners {:?}",
                tr,
                scan(tr),
                owner
            );
        }
    }
    for tr in &run.tracks {
        if !truth_sorted.contains(tr) {
            println!("extra map {:?} scans {:?}", tr, scan(tr));
        }
    }
}
pub fn gospa_parts(
    model: &Model,
    problem: &Problem,
    truth: &tracker_model::TrackSet,
    tracks: &[Vec<u32>],
) -> (f64, usize, usize, f64) {
    let est = smoothed_tracks(model, problem, tracks, 0).unwrap();
    let g = eval_metrics::gospa_over_time(
        truth,
        &est,
        &eval_metrics::OspaConfig {
            cutoff: 100.0,
            order: 2.0,
        },
    )
    .unwrap();
    let n = g.len() as f64;
    (
        g.iter().map(|x| x.1.distance).sum::<f64>() / n,
        g.iter().map(|x| x.1.n_missed).sum(),
        g.iter().map(|x| x.1.n_false).sum(),
        g.iter().map(|x| x.1.localisation).sum::<f64>() / n,
    )
}
