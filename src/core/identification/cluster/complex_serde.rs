//! Serialises a complex number as `[re, im]`.
use num_complex::Complex64;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

pub fn serialize<S: Serializer>(z: &Complex64, s: S) -> Result<S::Ok, S::Error> {
    [z.re, z.im].serialize(s)
}

pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Complex64, D::Error> {
    let [re, im] = <[f64; 2]>::deserialize(d)?;
    Ok(Complex64::new(re, im))
}
