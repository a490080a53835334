//! JUnit XML for the scenario suite (`cargo xtask scenarios --junit FILE`), the format CI
//! dashboards read: one test suite, one test case per scenario, a failure per failed scenario.

use std::fmt::Write as _;

use crate::scenario::Verdict;

/// The verdicts as a JUnit XML document.
pub fn xml(verdicts: &[Verdict]) -> String {
    let failures = verdicts.iter().filter(|v| !v.passed()).count();
    let total_s: f64 = verdicts.iter().map(|v| v.seconds).sum();
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        out,
        "<testsuites><testsuite name=\"scenarios\" tests=\"{}\" failures=\"{failures}\" errors=\"0\" time=\"{total_s:.3}\">",
        verdicts.len()
    );
    for v in verdicts {
        let _ = write!(
            out,
            "  <testcase classname=\"scenarios\" name=\"{}\" time=\"{:.3}\"",
            escape(&v.name),
            v.seconds
        );
        if v.passed() {
            let _ = writeln!(
                out,
                "><system-out>{}</system-out></testcase>",
                escape(&v.summary)
            );
        } else {
            let _ = writeln!(
                out,
                "><failure message=\"{}\">{}</failure></testcase>",
                escape(v.problems.first().map_or("", String::as_str)),
                escape(&v.problems.join("\n"))
            );
        }
    }
    out + "</testsuite></testsuites>\n"
}

/// Escapes the five XML special characters.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&apos;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failures_are_counted_and_text_is_escaped() {
        let verdicts = [
            Verdict {
                name: "a".into(),
                seconds: 1.5,
                problems: vec![],
                summary: "3 metrics match".into(),
            },
            Verdict {
                name: "b<&>".into(),
                seconds: 0.25,
                problems: vec!["x: got 1, expected \"2\"".into()],
                summary: String::new(),
            },
        ];
        let xml = xml(&verdicts);
        assert!(xml.contains("tests=\"2\" failures=\"1\""), "{xml}");
        assert!(
            xml.contains("name=\"b&lt;&amp;&gt;\" time=\"0.250\""),
            "{xml}"
        );
        assert!(
            xml.contains("<failure message=\"x: got 1, expected &quot;2&quot;\">"),
            "{xml}"
        );
        assert_eq!(xml.matches("<testcase").count(), 2);
    }
}
