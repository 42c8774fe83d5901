//! Serialises complex numbers as a list of `[re, im]`.
use num_complex::Complex64;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

pub fn serialize<S: Serializer>(zs: &[Complex64], s: S) -> Result<S::Ok, S::Error> {
    zs.iter().map(|z| [z.re, z.im]).collect::<Vec<_>>().serialize(s)
}

pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Complex64>, D::Error> {
    let pairs = Vec::<[f64; 2]>::deserialize(d)?;
    Ok(pairs.into_iter().map(|[re, im]| Complex64::new(re, im)).collect())
}
