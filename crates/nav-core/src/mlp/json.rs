//! Loading networks from the uasnav thermal-model JSON file (`std` feature).
//!
//! The file is written by Python (`uasnav.thermal`, schema version 1):
//!
//! ```json
//! {"format": "uasnav.thermal-model", "schema_version": 1, "kind": "neural",
//!  "units": {"input": "degC", "output": "rad/s", "derivative": "rad/s/degC"},
//!  "calibrated_range_c": [-20.5, 37.3],
//!  "models": [{"input_norm": {"offset": 8.4, "scale": 0.0346},
//!              "output_norm": {"offset": 1e-3, "scale": 2e-4},
//!              "layers": [{"activation": "tanh", "weights": [[..]], "biases": [..]}, …]}, …],
//!  "derivative_models": [ … same shape, output unit rad/s/degC … ] | null,
//!  "training": {…}, "checksum": {"algorithm": "sha256", "value": "…"}}
//! ```
//!
//! `weights` of a layer are `(outputs × inputs)` nested lists. The checksum is the SHA-256 of
//! the file's bytes with its own hex value replaced by 64 `0`s, so both loaders verify it
//! byte-exactly without re-serialising. This loader checks the checksum, format, schema
//! version, kind, units, shapes and finiteness: a corrupt or mismatched file is an error naming
//! what is wrong, never a silently wrong network.
// No unchecked indexing in library code (issue #20); a proven index carries an `allow`.
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]
use super::{Activation, Affine, LayerSpec, Mlp};
use serde::Deserialize;
use std::string::{String, ToString};
use std::vec::Vec;
use std::{fmt, format};

/// The `format` field every thermal-model file carries.
pub const FORMAT: &str = "uasnav.thermal-model";
/// The schema version this loader reads.
pub const SCHEMA_VERSION: u32 = 1;

/// A model file that could not be loaded, with a message naming the part at fault.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ModelFileError(pub String);

impl fmt::Display for ModelFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "thermal model file: {}", self.0)
    }
}

impl std::error::Error for ModelFileError {}

#[derive(Deserialize)]
struct Norm {
    offset: f64,
    scale: f64,
}

#[derive(Deserialize)]
struct LayerJson {
    activation: String,
    weights: Vec<Vec<f64>>,
    biases: Vec<f64>,
}

#[derive(Deserialize)]
struct NetJson {
    input_norm: Norm,
    output_norm: Norm,
    layers: Vec<LayerJson>,
}

#[derive(Deserialize)]
struct Units {
    input: String,
    output: String,
}

#[derive(Deserialize)]
struct Checksum {
    algorithm: String,
    value: String,
}

#[derive(Deserialize)]
struct FileJson {
    checksum: Checksum,
    format: String,
    schema_version: u32,
    kind: String,
    units: Units,
    calibrated_range_c: [f64; 2],
    models: Vec<serde_json::Value>,
    #[serde(default)]
    derivative_models: Option<Vec<serde_json::Value>>,
}

/// The networks of a neural thermal model: one bias network per axis and, if the file
/// holds them, the networks trained on ∂b/∂T (thesis eq. 37).
#[derive(Debug, Clone)]
pub struct ThermalNetworks {
    /// Bias networks, one per axis (output rad/s, input °C).
    pub bias: Vec<Mlp<f64>>,
    /// Derivative networks, one per axis (output rad/s/°C), if present.
    pub derivative: Option<Vec<Mlp<f64>>>,
    /// Calibrated temperature range `(min, max)` (°C).
    pub range_c: (f64, f64),
}

fn net_from_json(
    v: &serde_json::Value,
    range: (f64, f64),
    where_: &str,
) -> Result<Mlp<f64>, ModelFileError> {
    let n: NetJson =
        serde_json::from_value(v.clone()).map_err(|e| ModelFileError(format!("{where_}: {e}")))?;
    let mut flat: Vec<Vec<f64>> = Vec::with_capacity(n.layers.len());
    let mut acts = Vec::with_capacity(n.layers.len());
    let mut fan_in = 1usize;
    for (i, l) in n.layers.iter().enumerate() {
        if l.weights.len() != l.biases.len() {
            return Err(ModelFileError(format!(
                "{where_}: layer {i}: {} weight rows but {} biases",
                l.weights.len(),
                l.biases.len()
            )));
        }
        if let Some(r) = l.weights.iter().position(|row| row.len() != fan_in) {
            return Err(ModelFileError(format!(
                "{where_}: layer {i}: weight row {r} has {} entries, expected {fan_in}",
                l.weights.get(r).map_or(0, Vec::len)
            )));
        }
        fan_in = l.biases.len();
        flat.push(l.weights.iter().flatten().copied().collect());
        acts.push(Activation::from_name(&l.activation).map_err(|e| {
            ModelFileError(format!("{where_}: layer {i}: {e}: {:?}", l.activation))
        })?);
    }
    let specs: Vec<LayerSpec<'_, f64>> = n
        .layers
        .iter()
        .zip(flat.iter())
        .zip(acts.iter())
        .map(|((l, w), a)| LayerSpec {
            weights: w,
            biases: &l.biases,
            activation: *a,
        })
        .collect();
    Mlp::new(
        &specs,
        Affine {
            offset: n.input_norm.offset,
            scale: n.input_norm.scale,
        },
        Affine {
            offset: n.output_norm.offset,
            scale: n.output_norm.scale,
        },
        range,
    )
    .map_err(|e| ModelFileError(format!("{where_}: {e}")))
}

/// SHA-256 (lower-case hex) of `text` with the one occurrence of `value` replaced by 64 `0`s.
pub fn file_checksum(text: &str, value: &str) -> String {
    use sha2::{Digest, Sha256};
    let zeros = "0".repeat(64);
    let digest = Sha256::digest(text.replacen(value, &zeros, 1).as_bytes());
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

fn verify_checksum(text: &str, c: &Checksum) -> Result<(), ModelFileError> {
    if c.algorithm != "sha256" {
        return Err(ModelFileError(format!(
            "checksum algorithm {:?} is not supported (expected \"sha256\")",
            c.algorithm
        )));
    }
    let is_hex = c.value.len() == 64 && c.value.bytes().all(|b| b.is_ascii_hexdigit());
    if !is_hex || text.matches(c.value.as_str()).count() != 1 {
        return Err(ModelFileError(
            "checksum value is not a unique 64-digit hex string".to_string(),
        ));
    }
    let got = file_checksum(text, &c.value);
    if got != c.value {
        return Err(ModelFileError(format!(
            "checksum mismatch (file edited or corrupted): expected {}, got {got}",
            c.value
        )));
    }
    Ok(())
}

/// Parses a thermal-model file's text into its networks (checksum verified first).
pub fn load_thermal_model(text: &str) -> Result<ThermalNetworks, ModelFileError> {
    let f: FileJson = serde_json::from_str(text)
        .map_err(|e| ModelFileError(format!("not a valid model file: {e}")))?;
    verify_checksum(text, &f.checksum)?;
    if f.format != FORMAT {
        return Err(ModelFileError(format!(
            "format is {:?}, expected {FORMAT:?}",
            f.format
        )));
    }
    if f.schema_version != SCHEMA_VERSION {
        return Err(ModelFileError(format!(
            "schema_version {} is not supported (this build reads {SCHEMA_VERSION})",
            f.schema_version
        )));
    }
    if f.kind != "neural" {
        return Err(ModelFileError(format!(
            "kind {:?} holds no network (the Rust engine evaluates kind \"neural\")",
            f.kind
        )));
    }
    if f.units.input != "degC" || f.units.output != "rad/s" {
        return Err(ModelFileError(format!(
            "units input={:?} output={:?}, expected \"degC\" and \"rad/s\"",
            f.units.input, f.units.output
        )));
    }
    let range = (f.calibrated_range_c[0], f.calibrated_range_c[1]);
    if f.models.is_empty() {
        return Err(ModelFileError("models: empty".to_string()));
    }
    let bias = f
        .models
        .iter()
        .enumerate()
        .map(|(i, v)| net_from_json(v, range, &format!("models[{i}]")))
        .collect::<Result<Vec<_>, _>>()?;
    let derivative = match &f.derivative_models {
        None => None,
        Some(list) => Some(
            list.iter()
                .enumerate()
                .map(|(i, v)| net_from_json(v, range, &format!("derivative_models[{i}]")))
                .collect::<Result<Vec<_>, _>>()?,
        ),
    };
    Ok(ThermalNetworks {
        bias,
        derivative,
        range_c: range,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"{"format": "uasnav.thermal-model", "schema_version": 1, "kind": "neural",
      "units": {"input": "degC", "output": "rad/s", "derivative": "rad/s/degC"},
      "calibrated_range_c": [-20.0, 40.0],
      "models": [{"input_norm": {"offset": 10.0, "scale": 0.05},
                  "output_norm": {"offset": 0.001, "scale": 0.0002},
                  "layers": [{"activation": "tanh", "weights": [[0.8], [-1.3]], "biases": [0.1, 0.4]},
                             {"activation": "tanh", "weights": [[0.5, -0.7], [1.1, 0.3]], "biases": [-0.2, 0.05]},
                             {"activation": "linear", "weights": [[1.5, -0.6]], "biases": [0.02]}]}],
      "derivative_models": null, "training": {"anything": 1},
      "checksum": {"algorithm": "sha256", "value": "0000000000000000000000000000000000000000000000000000000000000000"}}"#;

    /// Signs a test file: its checksum is computed over the zero placeholder.
    fn signed(text: &str) -> String {
        let zeros = "0".repeat(64);
        let c = file_checksum(text, &zeros);
        text.replacen(&zeros, &c, 1)
    }

    #[test]
    fn loads_and_matches_closed_form() {
        let t = load_thermal_model(&signed(GOOD)).unwrap();
        assert_eq!(t.bias.len(), 1);
        assert_eq!(t.range_c, (-20.0, 40.0));
        let x: f64 = 25.0;
        let u = 0.05 * (x - 10.0);
        let h1 = [(0.8 * u + 0.1).tanh(), (-1.3 * u + 0.4).tanh()];
        let h2 = [
            (0.5 * h1[0] - 0.7 * h1[1] - 0.2).tanh(),
            (1.1 * h1[0] + 0.3 * h1[1] + 0.05).tanh(),
        ];
        let y = 1e-3 + 2e-4 * (1.5 * h2[0] - 0.6 * h2[1] + 0.02);
        assert!((t.bias[0].eval(x).value - y).abs() < 1e-16);
    }

    #[test]
    fn rejects_corrupt_and_mismatched_files() {
        let good = signed(GOOD);
        let edit = |from: &str, to: &str| signed(&GOOD.replace(from, to));
        let cases = [
            (
                edit("\"schema_version\": 1", "\"schema_version\": 9"),
                "schema_version 9",
            ),
            (edit("uasnav.thermal-model", "other"), "format"),
            (
                edit("\"kind\": \"neural\"", "\"kind\": \"polynomial\""),
                "kind",
            ),
            (
                edit("\"output\": \"rad/s\"", "\"output\": \"deg/s\""),
                "units",
            ),
            (
                edit("[[0.5, -0.7], [1.1, 0.3]]", "[[0.5], [1.1, 0.3]]"),
                "weight row 0",
            ),
            (edit("\"tanh\"", "\"relu\""), "activation"),
            (good[..200].to_string(), "not a valid model file"),
            (good.replace("0.8", "0.9"), "checksum mismatch"),
            (GOOD.to_string(), "checksum mismatch"),
            (good.replace("\"sha256\"", "\"md5\""), "algorithm"),
        ];
        for (text, needle) in cases {
            let e = load_thermal_model(&text).unwrap_err();
            assert!(
                e.to_string().contains(needle),
                "{e} should mention {needle}"
            );
        }
    }
}
