//! Fixed-length arrays in input files (`pitch`, `origin`, `pose`), refused at any other length.
//!
//! toml 0.8 fills a `[f64; N]` from the first N elements of a longer array and drops the rest
//! without a word (a 3-value `pitch`, a pose row of 5 numbers, a pose of 5 rows), while
//! serde_json refuses them. These deserialize through a `Vec` and check its length, so scene
//! files, hypothesis files and EXR headers all refuse the same mistakes.

use serde::de::{Deserialize, Deserializer, Error};

/// `#[serde(deserialize_with = "exact_array::array")]` for a `[f64; N]`.
pub fn array<'de, D: Deserializer<'de>, const N: usize>(deserializer: D) -> Result<[f64; N], D::Error> {
    exact(Vec::<f64>::deserialize(deserializer)?, "an array")
}

/// `#[serde(deserialize_with = "exact_array::matrix")]` for rows `[[f64; C]; R]`.
pub fn matrix<'de, D: Deserializer<'de>, const R: usize, const C: usize>(
    deserializer: D,
) -> Result<[[f64; C]; R], D::Error> {
    let rows = Vec::<Vec<f64>>::deserialize(deserializer)?;
    let rows: Vec<[f64; C]> = rows.into_iter().map(|row| exact(row, "each row")).collect::<Result<_, _>>()?;
    exact(rows, "a matrix")
}

/// `#[serde(default, deserialize_with = "exact_array::optional_array")]` for an optional key's
/// `Option<[f64; N]>`.
pub fn optional_array<'de, D: Deserializer<'de>, const N: usize>(
    deserializer: D,
) -> Result<Option<[f64; N]>, D::Error> {
    array(deserializer).map(Some)
}

/// `#[serde(default, deserialize_with = "exact_array::optional_matrix")]` for an optional key's
/// `Option<[[f64; C]; R]>`.
pub fn optional_matrix<'de, D: Deserializer<'de>, const R: usize, const C: usize>(
    deserializer: D,
) -> Result<Option<[[f64; C]; R]>, D::Error> {
    matrix(deserializer).map(Some)
}

fn exact<T, E: Error, const N: usize>(values: Vec<T>, what: &str) -> Result<[T; N], E> {
    let len = values.len();
    values.try_into().map_err(|_| E::custom(format!("{what} must hold exactly {N} values, not {len}")))
}
