//! Maps: the state space of a ground target (free cells of a grid with obstacles, or the
//! crossroads of a road graph), transitions from kinematic constraints, and an observation
//! model from sensors whose accuracy falls with distance (Huynh & Vu 2006 §5).

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};
use tracker_model::{
    Frame, Track, TrackId, TrackPoint, Vec2, ensure_non_negative, ensure_positive,
};

use crate::error::{Error, Result, invalid_parameter};
use crate::transitions::{Transitions, check_row};

/// A rectangular grid of square cells, some blocked by obstacles; checked by
/// [`StateSpace::from_grid`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
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

impl CellGrid {
    /// Checks that the grid has cells, that the cell size is finite and positive and that
    /// every blocked cell lies inside the grid.
    pub fn check(&self) -> Result<()> {
        if self.n_cols == 0 || self.n_rows == 0 {
            return Err(Error::Empty("cell grid"));
        }
        ensure_positive(self.cell_size, "cell_size")?;
        for &(col, row) in &self.blocked {
            if col >= self.n_cols || row >= self.n_rows {
                return Err(Error::CellOutsideGrid {
                    col,
                    row,
                    n_cols: self.n_cols,
                    n_rows: self.n_rows,
                });
            }
        }
        Ok(())
    }
}

/// The state of every cell of a grid, row-major, `None` when blocked.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CellStates {
    n_cols: usize,
    n_rows: usize,
    states: Vec<Option<usize>>,
}

/// Where a target can be and where it can go in one hop.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawStateSpace", into = "RawStateSpace")]
pub struct StateSpace {
    positions: Vec<Vec2>,
    neighbours: Vec<Vec<usize>>,
    /// For grids: the state of each cell.
    cells: Option<CellStates>,
}

/// The serialised form, re-checked on reading so that no index can point outside the states.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStateSpace {
    positions: Vec<Vec2>,
    neighbours: Vec<Vec<usize>>,
    cells: Option<CellStates>,
}

impl TryFrom<RawStateSpace> for StateSpace {
    type Error = Error;
    fn try_from(raw: RawStateSpace) -> Result<Self> {
        let n = raw.positions.len();
        if n == 0 {
            return Err(Error::Empty("state space"));
        }
        if raw
            .positions
            .iter()
            .any(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(Error::Model(tracker_model::Error::NonFinite {
                what: "state position",
            }));
        }
        if raw.neighbours.len() != n {
            return Err(Error::ShapeMismatch {
                what: "neighbour lists (one per state)",
                expected: n,
                got: raw.neighbours.len(),
            });
        }
        let out_of_range = |s: &usize| *s >= n;
        if let Some((i, _)) = raw
            .neighbours
            .iter()
            .enumerate()
            .find(|(_, v)| v.iter().any(out_of_range))
        {
            return Err(invalid_parameter(
                "neighbours",
                format!("state {i} lists a neighbour outside 0..{n}"),
            ));
        }
        if let Some(cells) = &raw.cells {
            if cells.states.len() != cells.n_cols * cells.n_rows {
                return Err(Error::ShapeMismatch {
                    what: "cell states (n_cols × n_rows)",
                    expected: cells.n_cols * cells.n_rows,
                    got: cells.states.len(),
                });
            }
            if cells.states.iter().flatten().any(out_of_range) {
                return Err(invalid_parameter(
                    "cells",
                    format!("a cell maps to a state outside 0..{n}"),
                ));
            }
        }
        Ok(Self {
            positions: raw.positions,
            neighbours: raw.neighbours,
            cells: raw.cells,
        })
    }
}

impl From<StateSpace> for RawStateSpace {
    fn from(s: StateSpace) -> Self {
        Self {
            positions: s.positions,
            neighbours: s.neighbours,
            cells: s.cells,
        }
    }
}

impl StateSpace {
    /// One state per free cell (row-major order), linked to its free 4-neighbours.
    pub fn from_grid(grid: &CellGrid) -> Result<Self> {
        grid.check()?;
        let mut blocked = vec![false; grid.n_cols * grid.n_rows];
        for &(c, r) in &grid.blocked {
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
            cells: Some(CellStates {
                n_cols: grid.n_cols,
                n_rows: grid.n_rows,
                states: cell_states,
            }),
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
                return Err(invalid_parameter(
                    "road",
                    format!("({a}, {b}) must join two different crossroads among 0..{n}"),
                ));
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
            cells: None,
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

    /// For a grid, the state of cell (`col`, `row`): `None` when the cell is blocked. Errors if
    /// the cell lies outside the grid, or if the state space is a road graph.
    pub fn state_of_cell(&self, col: usize, row: usize) -> Result<Option<usize>> {
        let cells = self.cells.as_ref().ok_or(Error::NotAGrid)?;
        if col >= cells.n_cols || row >= cells.n_rows {
            return Err(Error::CellOutsideGrid {
                col,
                row,
                n_cols: cells.n_cols,
                n_rows: cells.n_rows,
            });
        }
        Ok(cells.states[row * cells.n_cols + col])
    }

    /// The track of a state path (as returned by [`viterbi`](crate::viterbi) or
    /// [`posterior_decode`](crate::posterior_decode)): one point per time step, at the state's
    /// position, step t at frame `first_frame + t`, with no velocity or covariance. An empty
    /// path gives an empty track. Errors if a state is outside 0..N or the frames overflow.
    pub fn path_to_track(&self, path: &[usize], first_frame: Frame, id: TrackId) -> Result<Track> {
        let n = self.n_states();
        let points =
            path.iter()
                .enumerate()
                .map(|(t, &s)| {
                    if s >= n {
                        return Err(invalid_parameter(
                            "state path",
                            format!("step {t} is state {s}, but the map has {n} states"),
                        ));
                    }
                    let frame = Frame::try_from(t)
                    .ok()
                    .and_then(|t| first_frame.checked_add(t))
                    .ok_or_else(|| invalid_parameter("state path", format!(
                            "step {t} after first frame {first_frame} overflows the frame index"
                        )))?;
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
    /// always with the dominant diagonal Huynh & Vu (2006) describe.
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
#[serde(
    deny_unknown_fields,
    try_from = "RawSpeedDistribution",
    into = "RawSpeedDistribution"
)]
pub struct SpeedDistribution {
    probabilities: Vec<f64>,
}

/// The serialised form, checked by [`SpeedDistribution::new`] on reading.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSpeedDistribution {
    probabilities: Vec<f64>,
}

impl TryFrom<RawSpeedDistribution> for SpeedDistribution {
    type Error = Error;
    fn try_from(raw: RawSpeedDistribution) -> Result<Self> {
        Self::new(raw.probabilities)
    }
}

impl From<SpeedDistribution> for RawSpeedDistribution {
    fn from(s: SpeedDistribution) -> Self {
        Self {
            probabilities: s.probabilities,
        }
    }
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

/// Sensors at known positions and how their accuracy degrades with distance; checked by
/// [`StateSpace::sensor_emissions`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorModel {
    /// Sensor positions (at least one).
    pub sensors: Vec<Vec2>,
    /// Position spread right at a sensor (> 0).
    pub base_sigma: f64,
    /// Extra spread per unit of distance to the nearest sensor (≥ 0).
    pub sigma_per_distance: f64,
}

impl SensorModel {
    /// Checks that there is at least one sensor, every position is finite, `base_sigma` is
    /// finite and > 0 and `sigma_per_distance` finite and ≥ 0.
    pub fn check(&self) -> Result<()> {
        if self.sensors.is_empty() {
            return Err(Error::Empty("sensor list"));
        }
        if self
            .sensors
            .iter()
            .any(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(Error::Model(tracker_model::Error::NonFinite {
                what: "sensor position",
            }));
        }
        ensure_positive(self.base_sigma, "base_sigma")?;
        ensure_non_negative(self.sigma_per_distance, "sigma_per_distance")?;
        Ok(())
    }
}
