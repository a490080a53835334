//! Maps: the state space of a ground target (free cells of a grid with obstacles, or the
//! crossroads of a road graph), transitions from kinematic constraints, and an observation
//! model from sensors whose accuracy falls with distance (seed 002 §5).

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};
use tracker_model::{Frame, Track, TrackId, TrackPoint, Vec2};

use crate::error::{Error, Result};
use crate::model::{Transitions, check_row};

/// A rectangular grid of square cells, some blocked by obstacles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellGrid {
    /// Columns.
    pub n_cols: usize,
    /// Rows.
    pub n_rows: usize,
    /// Side of a cell (map units).
    pub cell_size: f64,
    /// Blocked cells as (column, row).
    pub blocked: Vec<(usize, usize)>,
}

/// Where a target can be and where it can go in one hop.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StateSpace {
    positions: Vec<Vec2>,
    neighbours: Vec<Vec<usize>>,
    /// For grids: the state of each cell (row-major), `None` when blocked.
    cell_states: Option<Vec<Option<usize>>>,
}

impl StateSpace {
    /// One state per free cell (row-major order), linked to its free 4-neighbours.
    pub fn from_grid(grid: &CellGrid) -> Result<Self> {
        if grid.n_cols == 0 || grid.n_rows == 0 {
            return Err(Error::Empty("cell grid"));
        }
        if !(grid.cell_size.is_finite() && grid.cell_size > 0.0) {
            return Err(Error::InvalidParameter {
                name: "cell_size",
                reason: format!("{} must be finite and > 0", grid.cell_size),
            });
        }
        let mut blocked = vec![false; grid.n_cols * grid.n_rows];
        for &(c, r) in &grid.blocked {
            if c >= grid.n_cols || r >= grid.n_rows {
                return Err(Error::InvalidParameter {
                    name: "blocked cell",
                    reason: format!(
                        "({c}, {r}) is outside the {}×{} grid",
                        grid.n_cols, grid.n_rows
                    ),
                });
            }
            blocked[r * grid.n_cols + c] = true;
        }
        let mut cell_states = vec![None; blocked.len()];
        let mut positions = Vec::new();
        for r in 0..grid.n_rows {
            for c in 0..grid.n_cols {
                if !blocked[r * grid.n_cols + c] {
                    cell_states[r * grid.n_cols + c] = Some(positions.len());
                    positions.push(Vec2::new(
                        (c as f64 + 0.5) * grid.cell_size,
                        (r as f64 + 0.5) * grid.cell_size,
                    ));
                }
            }
        }
        if positions.is_empty() {
            return Err(Error::Empty("set of free cells"));
        }
        let mut neighbours = vec![Vec::new(); positions.len()];
        for r in 0..grid.n_rows {
            for c in 0..grid.n_cols {
                let Some(s) = cell_states[r * grid.n_cols + c] else {
                    continue;
                };
                let candidates = [
                    (c.wrapping_sub(1), r),
                    (c + 1, r),
                    (c, r.wrapping_sub(1)),
                    (c, r + 1),
                ];
                for (nc, nr) in candidates {
                    if nc < grid.n_cols
                        && nr < grid.n_rows
                        && let Some(t) = cell_states[nr * grid.n_cols + nc]
                    {
                        neighbours[s].push(t);
                    }
                }
                neighbours[s].sort_unstable();
            }
        }
        Ok(Self {
            positions,
            neighbours,
            cell_states: Some(cell_states),
        })
    }

    /// One state per crossroad of a road graph; `roads` are undirected edges between them.
    pub fn from_road_graph(crossroads: Vec<Vec2>, roads: &[(usize, usize)]) -> Result<Self> {
        if crossroads.is_empty() {
            return Err(Error::Empty("road graph"));
        }
        if crossroads
            .iter()
            .any(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(Error::Model(tracker_model::Error::NonFinite {
                what: "crossroad position",
            }));
        }
        let n = crossroads.len();
        let mut neighbours = vec![Vec::new(); n];
        for &(a, b) in roads {
            if a >= n || b >= n || a == b {
                return Err(Error::InvalidParameter {
                    name: "road",
                    reason: format!("({a}, {b}) must join two different crossroads among 0..{n}"),
                });
            }
            neighbours[a].push(b);
            neighbours[b].push(a);
        }
        for v in &mut neighbours {
            v.sort_unstable();
            v.dedup();
        }
        Ok(Self {
            positions: crossroads,
            neighbours,
            cell_states: None,
        })
    }

    /// N.
    pub fn n_states(&self) -> usize {
        self.positions.len()
    }

    /// Where state `i` is.
    pub fn position(&self, i: usize) -> Vec2 {
        self.positions[i]
    }

    /// All positions, by state.
    pub fn positions(&self) -> &[Vec2] {
        &self.positions
    }

    /// States one hop from `i`.
    pub fn neighbours(&self, i: usize) -> &[usize] {
        &self.neighbours[i]
    }

    /// For a grid, the state of cell (`col`, `row`), if free.
    pub fn state_of_cell(&self, col: usize, row: usize, n_cols: usize) -> Option<usize> {
        self.cell_states
            .as_ref()?
            .get(row * n_cols + col)
            .copied()
            .flatten()
    }

    /// The track of a state path (as returned by [`viterbi`](crate::viterbi) or
    /// [`posterior_decode`](crate::posterior_decode)): one point per time step, at the state's
    /// position, step t at frame `first_frame + t`, with no velocity or covariance. An empty
    /// path gives an empty track. Errors if a state is outside 0..N or the frames overflow.
    pub fn path_to_track(&self, path: &[usize], first_frame: Frame, id: TrackId) -> Result<Track> {
        let n = self.n_states();
        let points = path
            .iter()
            .enumerate()
            .map(|(t, &s)| {
                if s >= n {
                    return Err(Error::InvalidParameter {
                        name: "state path",
                        reason: format!("step {t} is state {s}, but the map has {n} states"),
                    });
                }
                let frame = Frame::try_from(t)
                    .ok()
                    .and_then(|t| first_frame.checked_add(t))
                    .ok_or_else(|| Error::InvalidParameter {
                        name: "state path",
                        reason: format!(
                            "step {t} after first frame {first_frame} overflows the frame index"
                        ),
                    })?;
                Ok(TrackPoint::at(frame, self.positions[s]))
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Track::from_points(id, points)?)
    }

    /// States reachable from `from` in at most `max_hops` hops, with their hop distance.
    fn hop_distances(&self, from: usize, max_hops: usize) -> Vec<(usize, usize)> {
        let mut dist = vec![usize::MAX; self.n_states()];
        dist[from] = 0;
        let mut queue = VecDeque::from([from]);
        let mut out = vec![(from, 0)];
        while let Some(s) = queue.pop_front() {
            if dist[s] == max_hops {
                continue;
            }
            for &t in &self.neighbours[s] {
                if dist[t] == usize::MAX {
                    dist[t] = dist[s] + 1;
                    out.push((t, dist[t]));
                    queue.push_back(t);
                }
            }
        }
        out
    }

    /// Transitions from kinematic constraints: the target moves k hops in one step with
    /// probability `speed.probabilities[k]`, spread evenly over the states exactly k hops away.
    /// Where no state lies k hops away (a dead end), that probability is shared among the
    /// speeds that are possible, so every row sums to 1. Stored sparse.
    pub fn transitions(&self, speed: &SpeedDistribution) -> Result<Transitions> {
        let max_hops = speed.probabilities.len() - 1;
        let rows = (0..self.n_states())
            .map(|i| {
                let reach = self.hop_distances(i, max_hops);
                let mut count = vec![0usize; max_hops + 1];
                reach.iter().for_each(|&(_, d)| count[d] += 1);
                let possible: f64 = speed
                    .probabilities
                    .iter()
                    .zip(&count)
                    .filter(|(_, c)| **c > 0)
                    .map(|(p, _)| p)
                    .sum();
                let mut row: Vec<(usize, f64)> = reach
                    .iter()
                    .map(|&(j, d)| (j, speed.probabilities[d] / (count[d] as f64 * possible)))
                    .filter(|e| e.1 > 0.0)
                    .collect();
                row.sort_by_key(|e| e.0);
                row
            })
            .collect();
        Transitions::sparse(rows)
    }

    /// Emission matrix (symbols = states, M = N): the symbol is the state a coarse position
    /// fix points at. From state i the fix lands on state m with probability
    /// ∝ exp(−‖p_i − p_m‖² / 2σ_i²), where σ_i = `base_sigma` + `sigma_per_distance` × the
    /// distance from i to the nearest sensor: accurate near a sensor, vaguer away from one,
    /// always with the dominant diagonal the seed describes.
    pub fn sensor_emissions(&self, sensors: &SensorModel) -> Result<Vec<f64>> {
        sensors.check()?;
        let n = self.n_states();
        let mut out = Vec::with_capacity(n * n);
        for i in 0..n {
            let p = self.positions[i];
            let nearest = sensors
                .sensors
                .iter()
                .map(|s| (s - p).norm())
                .fold(f64::INFINITY, f64::min);
            let sigma = sensors.base_sigma + sensors.sigma_per_distance * nearest;
            let row: Vec<f64> = self
                .positions
                .iter()
                .map(|q| (-(q - p).norm_squared() / (2.0 * sigma * sigma)).exp())
                .collect();
            let total: f64 = row.iter().sum();
            out.extend(row.iter().map(|v| v / total));
            check_row(&out[i * n..], "emission matrix", i)?;
        }
        Ok(out)
    }
}

/// P(the target moves k hops in one step), k = 0, 1, …
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpeedDistribution {
    probabilities: Vec<f64>,
}

impl SpeedDistribution {
    /// Checks that the probabilities form a distribution.
    pub fn new(probabilities: Vec<f64>) -> Result<Self> {
        if probabilities.is_empty() {
            return Err(Error::Empty("speed distribution"));
        }
        check_row(&probabilities, "speed distribution", 0)?;
        Ok(Self { probabilities })
    }

    /// The probabilities by hop count.
    pub fn probabilities(&self) -> &[f64] {
        &self.probabilities
    }
}

/// Sensors at known positions and how their accuracy degrades with distance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorModel {
    /// Sensor positions (at least one).
    pub sensors: Vec<Vec2>,
    /// Position spread right at a sensor (> 0).
    pub base_sigma: f64,
    /// Extra spread per unit of distance to the nearest sensor (≥ 0).
    pub sigma_per_distance: f64,
}

impl SensorModel {
    fn check(&self) -> Result<()> {
        if self.sensors.is_empty() {
            return Err(Error::Empty("sensor list"));
        }
        let base_ok = self.base_sigma.is_finite() && self.base_sigma > 0.0;
        let slope_ok = self.sigma_per_distance.is_finite() && self.sigma_per_distance >= 0.0;
        if !(base_ok && slope_ok) {
            return Err(Error::InvalidParameter {
                name: "sensor accuracy",
                reason: format!(
                    "base_sigma {} must be > 0 and sigma_per_distance {} >= 0",
                    self.base_sigma, self.sigma_per_distance
                ),
            });
        }
        Ok(())
    }
}
