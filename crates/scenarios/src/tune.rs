//! Reproducible tuning: the searches behind a scenario's settings, run by `cargo xtask tune
//! NAME` on the scenario's tuning seeds only. The chosen settings are written to a file the
//! scenario reads (`fixtures/tuned/NAME.toml`), and every candidate's score to a CSV beside it
//! that the report's appendix shows, so no tuned number is copied by hand.

use std::fmt::Write as _;

use anyhow::{Result, bail};
use serde::Deserialize;

/// The most rounds a coordinate search may run.
pub const MAX_ROUNDS: usize = 20;

/// The most candidates one coordinate may have.
pub const MAX_CANDIDATES: usize = 64;

/// What a tuning search chose, and how it chose it.
#[derive(Debug, Clone, PartialEq)]
pub struct Tuned {
    /// The settings file (TOML, a header comment then the chosen values) the scenario reads.
    pub settings: String,
    /// Every candidate the search scored, as CSV with a header line.
    pub grid: String,
}

/// One setting a coordinate search varies: a dotted key of the settings table (e.g.
/// `offline.link_gap_factor`) and its candidates, in the order they are tried.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Coordinate {
    /// Dotted path in the settings table.
    pub key: String,
    /// Candidate values (TOML values of the setting's type).
    pub values: Vec<toml::Value>,
}

/// One scored candidate.
#[derive(Debug, Clone, PartialEq)]
pub struct GridRow {
    /// Round of the search (1-based).
    pub round: usize,
    /// The coordinate's key.
    pub key: String,
    /// The candidate, as TOML writes it.
    pub value: String,
    /// Its score (higher is better).
    pub score: f64,
    /// Whether the search kept it after this coordinate's step.
    pub chosen: bool,
}

/// Checks a search's shape: 1 ≤ rounds ≤ [`MAX_ROUNDS`], each coordinate with 1 to
/// [`MAX_CANDIDATES`] candidates, and no key twice.
pub fn check_coordinates(coordinates: &[Coordinate], max_rounds: usize) -> Result<()> {
    if !(1..=MAX_ROUNDS).contains(&max_rounds) {
        bail!("max_rounds = {max_rounds}: must be 1 to {MAX_ROUNDS}");
    }
    for (i, c) in coordinates.iter().enumerate() {
        if c.values.is_empty() || c.values.len() > MAX_CANDIDATES {
            bail!(
                "coordinate {:?} has {} candidates: must be 1 to {MAX_CANDIDATES}",
                c.key,
                c.values.len()
            );
        }
        if coordinates[..i].iter().any(|other| other.key == c.key) {
            bail!("coordinate {:?} is given twice", c.key);
        }
        if c.key.split('.').any(str::is_empty) {
            bail!("coordinate key {:?} has an empty part", c.key);
        }
    }
    Ok(())
}

/// Sets `table[key]` (a dotted path; tables on the way are created) to `value`.
pub fn set_dotted(table: &mut toml::Table, key: &str, value: toml::Value) -> Result<()> {
    let mut parts: Vec<&str> = key.split('.').collect();
    let Some(last) = parts.pop() else {
        bail!("empty key");
    };
    let mut at = table;
    for part in parts {
        let entry = at
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        let toml::Value::Table(next) = entry else {
            bail!("{key}: {part} is not a table");
        };
        at = next;
    }
    at.insert(last.to_string(), value);
    Ok(())
}

/// Coordinate ascent: from `start`, each coordinate in turn takes its best candidate with the
/// others held (ties keep the last round's choice, else the earlier candidate), round after
/// round, until
/// a round changes nothing or `max_rounds` have run. `score(settings, coordinate)` scores a
/// settings table for the coordinate's index (a search may score each coordinate by what it
/// affects); it must be deterministic. Returns the settings and every scored candidate.
pub fn coordinate_search(
    start: &toml::Table,
    coordinates: &[Coordinate],
    max_rounds: usize,
    mut score: impl FnMut(&toml::Table, usize) -> Result<f64>,
    log: &dyn Fn(&str),
) -> Result<(toml::Table, Vec<GridRow>)> {
    check_coordinates(coordinates, max_rounds)?;
    let mut settings = start.clone();
    let mut chosen: Vec<Option<usize>> = vec![None; coordinates.len()];
    let mut grid: Vec<GridRow> = Vec::new();
    for round in 1..=max_rounds {
        let mut changed = false;
        for (i, c) in coordinates.iter().enumerate() {
            let mut scores = Vec::with_capacity(c.values.len());
            for value in &c.values {
                let mut trial = settings.clone();
                set_dotted(&mut trial, &c.key, value.clone())?;
                let s = score(&trial, i)?;
                if !s.is_finite() {
                    bail!("{} = {value}: the score is {s}", c.key);
                }
                scores.push(s);
            }
            let j = best_candidate(&scores, chosen[i]);
            for (k, (value, &s)) in c.values.iter().zip(&scores).enumerate() {
                grid.push(GridRow {
                    round,
                    key: c.key.clone(),
                    value: value.to_string(),
                    score: s,
                    chosen: k == j,
                });
            }
            log(&format!(
                "round {round}: {} = {} ({:.4})",
                c.key, c.values[j], scores[j]
            ));
            set_dotted(&mut settings, &c.key, c.values[j].clone())?;
            changed |= chosen[i] != Some(j);
            chosen[i] = Some(j);
        }
        if !changed {
            break;
        }
    }
    Ok((settings, grid))
}

/// The index of the highest score: among equal highest, the incumbent (the candidate chosen in
/// the last round), else the first, so that a setting no candidate improves never moves.
fn best_candidate(scores: &[f64], incumbent: Option<usize>) -> usize {
    // Exact equality on purpose: a tie is the same score to the bit (the scores are
    // deterministic), as when a setting changes nothing the score reads.
    let top = scores.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let is_top = |s: &f64| s.total_cmp(&top).is_eq();
    match incumbent {
        Some(k) if scores.get(k).is_some_and(is_top) => k,
        _ => scores.iter().position(is_top).unwrap_or(0),
    }
}

/// The grid as CSV: `round,key,value,score,chosen`, scores to 6 decimals.
pub fn grid_csv(rows: &[GridRow]) -> String {
    let mut csv = String::from("round,key,value,score,chosen\n");
    for r in rows {
        let value = r.value.replace('"', "'");
        let _ = writeln!(
            csv,
            "{},{},\"{value}\",{:.6},{}",
            r.round, r.key, r.score, r.chosen
        );
    }
    csv
}

/// The settings file: `header` as comment lines, then the settings as TOML.
pub fn settings_file(header: &str, settings: &toml::Table) -> Result<String> {
    let mut text = String::new();
    for line in header.lines() {
        let _ = writeln!(text, "# {line}");
    }
    text.push('\n');
    text.push_str(&toml::to_string(settings)?);
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn coordinate(key: &str, values: &[i64]) -> Coordinate {
        Coordinate {
            key: key.into(),
            values: values.iter().map(|&v| toml::Value::Integer(v)).collect(),
        }
    }

    fn get(t: &toml::Table, a: &str, b: &str) -> i64 {
        t[a][b].as_integer().unwrap()
    }

    #[test]
    fn coordinate_search_finds_the_separable_optimum_and_logs_every_candidate() {
        // score = −(x − 3)² − (y + 1)², optimum x = 3, y = −1: brute force over the grid agrees.
        let coords = [
            coordinate("a.x", &[0, 1, 2, 3, 4]),
            coordinate("b.y", &[-2, -1, 0]),
        ];
        let score = |t: &toml::Table, _: usize| {
            let x = t.get("a").map_or(0, |_| get(t, "a", "x")) as f64;
            let y = t.get("b").map_or(0, |_| get(t, "b", "y")) as f64;
            Ok(-(x - 3.0).powi(2) - (y + 1.0).powi(2))
        };
        let (best, grid) =
            coordinate_search(&toml::Table::new(), &coords, 5, score, &|_| {}).unwrap();
        assert_eq!((get(&best, "a", "x"), get(&best, "b", "y")), (3, -1));
        // Round 1 changes both, round 2 confirms: 2 × 8 rows, one chosen per coordinate step.
        assert_eq!(grid.len(), 16);
        assert_eq!(grid.iter().filter(|r| r.chosen).count(), 4);
        let csv = grid_csv(&grid);
        assert!(csv.starts_with("round,key,value,score,chosen\n1,a.x,\"0\","));
    }

    #[test]
    fn ties_keep_the_first_candidate_and_bad_shapes_are_refused() {
        let coords = [coordinate("x", &[5, 6, 7])];
        let (best, _) =
            coordinate_search(&toml::Table::new(), &coords, 3, |_, _| Ok(1.0), &|_| {}).unwrap();
        assert_eq!(best["x"].as_integer(), Some(5));
        // A tie with the incumbent keeps it; a better candidate replaces it.
        assert_eq!(best_candidate(&[1.0, 2.0, 2.0], Some(2)), 2);
        assert_eq!(best_candidate(&[1.0, 2.0, 2.0], Some(0)), 1);
        assert_eq!(best_candidate(&[3.0, 2.0, 2.0], Some(2)), 0);
        assert!(check_coordinates(&coords, 0).is_err());
        assert!(check_coordinates(&coords, MAX_ROUNDS + 1).is_err());
        assert!(check_coordinates(&[coordinate("x", &[])], 1).is_err());
        assert!(check_coordinates(&[coordinate("x", &[1]), coordinate("x", &[2])], 1).is_err());
        assert!(check_coordinates(&[coordinate("a..b", &[1])], 1).is_err());
        let nan = coordinate_search(
            &toml::Table::new(),
            &coords,
            1,
            |_, _| Ok(f64::NAN),
            &|_| {},
        );
        assert!(nan.is_err());
    }

    #[test]
    fn the_settings_file_reads_back_to_the_settings() {
        let mut t = toml::Table::new();
        set_dotted(&mut t, "offline.link_gap_factor", toml::Value::Float(1.5)).unwrap();
        set_dotted(
            &mut t,
            "scores.gnn_min_log_ratio",
            toml::Value::Float(f64::NEG_INFINITY),
        )
        .unwrap();
        let text = settings_file("written by a test\nsecond line", &t).unwrap();
        assert!(text.starts_with("# written by a test\n# second line\n\n"));
        let back: toml::Table = toml::from_str(&text).unwrap();
        assert_eq!(back, t);
    }
}
