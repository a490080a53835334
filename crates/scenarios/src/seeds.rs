//! The seed-use rule of `docs/seeds.md`: tuning, reported and fresh seeds are three disjoint
//! sets, checked by code wherever a scenario names more than one of them.

use anyhow::{Result, bail};

/// Fails when two of the named seed sets share a seed (or one set names a seed twice), naming
/// both sets: a seed used to choose a setting cannot also be evidence for it.
pub fn check_disjoint(sets: &[(&str, &[u64])]) -> Result<()> {
    for (i, (name, seeds)) in sets.iter().enumerate() {
        for (k, seed) in seeds.iter().enumerate() {
            if seeds[..k].contains(seed) {
                bail!("seed {seed} appears twice among the {name} seeds");
            }
            if let Some((other, _)) = sets[..i].iter().find(|(_, s)| s.contains(seed)) {
                bail!(
                    "seed {seed} is both a {other} seed and a {name} seed; docs/seeds.md keeps \
                     the two apart"
                );
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_and_repeated_seeds_are_refused_by_name() {
        assert!(
            check_disjoint(&[("tuning", &[1, 2]), ("reported", &[3]), ("fresh", &[4])]).is_ok()
        );
        let err = check_disjoint(&[("tuning", &[1, 2]), ("reported", &[3]), ("fresh", &[2])])
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("seed 2 is both a tuning seed and a fresh seed"),
            "{err}"
        );
        let err = check_disjoint(&[("reported", &[5, 5])])
            .unwrap_err()
            .to_string();
        assert!(err.contains("twice among the reported"), "{err}");
    }
}
