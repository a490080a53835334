//! Numbers in README.md, ARCHITECTURE.md and `docs/` that come from a scenario carry a marker
//! right after them, `0.946<!--fx mot-realistic fresh_mcmcda_mota_mean-->` (invisible in the
//! rendered page), optionally with a scale, `22.7<!--fx phd-images-eth-1
//! fresh_fused_image_minus_global_sr ×100-->`. The test below fails when a marked number is not
//! the metric of `fixtures/expected/NAME.json` rounded to the digits written, so a re-bless
//! that moves a documented number cannot leave the text stale.

use std::collections::BTreeMap;

/// The opening of a marker.
const MARKER: &str = "<!--fx ";

/// One marked number: where it is, what is written, and what it claims to be.
#[derive(Debug, PartialEq)]
struct Marked {
    line: usize,
    written: String,
    scenario: String,
    metric: String,
    scale: f64,
}

/// Every marker of `text`, with the number just before it; an error names a malformed one.
fn markers(text: &str) -> Result<Vec<Marked>, String> {
    let mut found = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let mut rest = line;
        let mut before_len = 0;
        while let Some(at) = rest.find(MARKER) {
            let before = &line[..before_len + at];
            let written: String = before
                .chars()
                .rev()
                .take_while(|c| c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | '−'))
                .collect::<Vec<_>>()
                .into_iter()
                .rev()
                .collect();
            let after = &rest[at + MARKER.len()..];
            let end = after
                .find("-->")
                .ok_or_else(|| format!("line {}: unclosed marker", i + 1))?;
            let fields: Vec<&str> = after[..end].split_whitespace().collect();
            let scale = match fields.get(2) {
                None => 1.0,
                Some(s) => s
                    .strip_prefix('×')
                    .and_then(|k| k.parse().ok())
                    .ok_or_else(|| format!("line {}: bad scale {s:?}", i + 1))?,
            };
            if written.is_empty() || fields.len() < 2 || fields.len() > 3 {
                return Err(format!(
                    "line {}: a marker needs a number before it and \"NAME METRIC [×K]\"",
                    i + 1
                ));
            }
            found.push(Marked {
                line: i + 1,
                written,
                scenario: fields[0].into(),
                metric: fields[1].into(),
                scale,
            });
            let consumed = at + MARKER.len() + end + 3;
            before_len += consumed;
            rest = &rest[consumed..];
        }
    }
    Ok(found)
}

/// Whether `written` is `value` rounded to the decimals it shows.
fn agrees(written: &str, value: f64) -> bool {
    let Ok(number) = written.replace('−', "-").parse::<f64>() else {
        return false;
    };
    let decimals = written.split_once('.').map_or(0, |(_, d)| d.len());
    let half_step = 0.5 * 10f64.powi(-i32::try_from(decimals).unwrap_or(0));
    (number - value).abs() <= half_step * (1.0 + 1e-9)
}

/// The disagreements of one file's markers with the metrics `lookup` gives.
fn check(
    file: &str,
    text: &str,
    lookup: &mut dyn FnMut(&str) -> Option<BTreeMap<String, f64>>,
) -> Vec<String> {
    let marked = match markers(text) {
        Ok(m) => m,
        Err(e) => return vec![format!("{file}: {e}")],
    };
    let mut problems = Vec::new();
    for m in marked {
        let value = lookup(&m.scenario).and_then(|metrics| metrics.get(&m.metric).copied());
        match value {
            None => problems.push(format!(
                "{file}:{}: no metric {} in fixtures/expected/{}.json",
                m.line, m.metric, m.scenario
            )),
            Some(v) if !agrees(&m.written, v * m.scale) => problems.push(format!(
                "{file}:{}: {} is written, the fixture's {}.{} gives {}",
                m.line,
                m.written,
                m.scenario,
                m.metric,
                v * m.scale
            )),
            Some(_) => {}
        }
    }
    problems
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn markers_parse_and_compare_by_the_digits_written() {
        let text = "MOTA 0.946<!--fx s a--> and 22.7<!--fx t b ×100--> points, −0.03<!--fx s c-->";
        let m = markers(text).unwrap();
        assert_eq!(m.len(), 3);
        assert_eq!((m[1].written.as_str(), m[1].scale), ("22.7", 100.0));
        let metrics = |name: &str| {
            let pairs: &[(&str, f64)] = match name {
                "s" => &[("a", 0.94551), ("c", -0.0251)],
                "t" => &[("b", 0.2274)],
                _ => return None,
            };
            Some(pairs.iter().map(|&(k, v)| (k.to_string(), v)).collect())
        };
        assert!(check("f", text, &mut |n| metrics(n)).is_empty());
        // One digit off, an unknown metric, a malformed marker: each is reported.
        let bad = "0.947<!--fx s a--> 1<!--fx s nope--> x<!--fx s a-->";
        let problems = check("f", bad, &mut |n| metrics(n));
        assert_eq!(problems.len(), 1, "{problems:?}");
        assert!(problems[0].contains("needs a number"), "{problems:?}");
        let problems = check("f", "0.947<!--fx s a--> 1<!--fx s nope-->", &mut |n| {
            metrics(n)
        });
        assert_eq!(problems.len(), 2, "{problems:?}");
    }

    #[test]
    fn documented_numbers_agree_with_the_fixtures() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let mut files = vec![root.join("README.md"), root.join("ARCHITECTURE.md")];
        for entry in std::fs::read_dir(root.join("docs")).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "md") {
                files.push(path);
            }
        }
        let mut lookup = |name: &str| {
            let path = root.join("fixtures/expected").join(format!("{name}.json"));
            serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
        };
        let mut problems = Vec::new();
        let mut n_marked = 0;
        for file in &files {
            let text = std::fs::read_to_string(file).unwrap();
            n_marked += text.matches(MARKER).count();
            problems.extend(check(&file.display().to_string(), &text, &mut lookup));
        }
        assert!(problems.is_empty(), "{}", problems.join("\n"));
        assert!(
            n_marked > 0,
            "no marked number found: the check would pass vacuously"
        );
    }
}
