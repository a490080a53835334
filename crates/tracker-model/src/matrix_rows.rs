//! Matrices in configuration files as lists of rows: `measurement_noise = [[1.0, 0.0], [0.0,
//! 1.0]]`. Use it on a config's matrix field with `#[serde(with = "tracker_model::matrix_rows")]`.
//!
//! Serialisation always writes rows. Human-readable formats (TOML, JSON) also accept the flat
//! form nalgebra's own serde writes, `[1.0, 0.0, 0.0, 1.0]`, read in nalgebra's column-major
//! order, so files written before the row form still load. Binary formats (bincode) read rows
//! only: they cannot look ahead to tell the two forms apart.

use std::fmt;

use nalgebra::SMatrix;
use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::ser::{SerializeSeq, Serializer};

/// Writes `m` as R rows of C numbers.
pub fn serialize<S: Serializer, const R: usize, const C: usize>(
    m: &SMatrix<f64, R, C>,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    let mut seq = serializer.serialize_seq(Some(R))?;
    for row in m.row_iter() {
        let values: Vec<f64> = row.iter().copied().collect();
        seq.serialize_element(&values)?;
    }
    seq.end()
}

/// Reads R rows of C numbers or, in a human-readable format, R·C numbers in column-major order.
pub fn deserialize<'de, D: Deserializer<'de>, const R: usize, const C: usize>(
    deserializer: D,
) -> Result<SMatrix<f64, R, C>, D::Error> {
    if deserializer.is_human_readable() {
        deserializer.deserialize_seq(MatrixVisitor::<R, C>)
    } else {
        let rows = Vec::<Vec<f64>>::deserialize(deserializer)?;
        from_rows(&rows).map_err(de::Error::custom)
    }
}

/// The matrix of `rows`, or what is wrong with their shape.
fn from_rows<const R: usize, const C: usize>(
    rows: &[Vec<f64>],
) -> Result<SMatrix<f64, R, C>, String> {
    if rows.len() != R || rows.iter().any(|r| r.len() != C) {
        let lens: Vec<usize> = rows.iter().map(Vec::len).collect();
        return Err(format!(
            "expected a {R}×{C} matrix as {R} rows of {C} numbers, found rows of lengths {lens:?}"
        ));
    }
    Ok(SMatrix::from_fn(|i, j| rows[i][j]))
}

/// One element of the outer list: a number (flat form) or a row.
#[derive(Deserialize)]
#[serde(untagged)]
enum Element {
    Number(f64),
    Row(Vec<f64>),
}

struct MatrixVisitor<const R: usize, const C: usize>;

impl<'de, const R: usize, const C: usize> Visitor<'de> for MatrixVisitor<R, C> {
    type Value = SMatrix<f64, R, C>;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "a {R}×{C} matrix as {R} rows of {C} numbers, e.g. [[1.0, 0.0], [0.0, 1.0]]"
        )
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let mut numbers = Vec::new();
        let mut rows = Vec::new();
        while let Some(element) = seq.next_element::<Element>()? {
            match element {
                Element::Number(v) => numbers.push(v),
                Element::Row(r) => rows.push(r),
            }
        }
        match (numbers.is_empty(), rows.is_empty()) {
            (true, _) => from_rows(&rows).map_err(de::Error::custom),
            (false, true) if numbers.len() == R * C => Ok(SMatrix::from_column_slice(&numbers)),
            (false, true) => Err(de::Error::custom(format!(
                "expected a {R}×{C} matrix as {R} rows of {C} numbers (or {} numbers in \
                 column-major order), found {} numbers",
                R * C,
                numbers.len()
            ))),
            (false, false) => Err(de::Error::custom(format!(
                "a {R}×{C} matrix mixes numbers and rows; write {R} rows of {C} numbers"
            ))),
        }
    }
}
