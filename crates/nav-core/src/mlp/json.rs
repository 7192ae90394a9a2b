//! Loading networks from the uasnav thermal-model JSON file (`std` feature).
//!
//! The file is written by Python (`uasnav.thermal`, schema version 1):
//!
//! ```json
//! {"format": "uasnav.thermal-model", "schema_version": 1, "kind": "neural",
//!  "quantity": "gyro_bias", "axes": ["x", "y", "z"],
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
//! byte-exactly without re-serialising.
//!
//! # Validation
//!
//! A file is validated fully at load, as Python's `uasnav.thermal.load_model` does, and every
//! error names the JSON key at fault (`models[1].input_norm.scale: …`): checksum, format and
//! schema version first (an edited file is refused as such); then no unknown top-level key,
//! `kind` `"neural"`, `quantity` `"gyro_bias"`, the exact `units`, a `calibrated_range_c` of
//! two finite numbers within [`TEMP_MIN_C`]…[`TEMP_MAX_C`] °C with min < max, 1…[`MAX_AXES`]
//! `models` with as many distinct string `axes`, `derivative_models` null or one per axis, a
//! `training` object if present; each network's keys, shapes, finite numbers and normalisation
//! scales > 0. Finally every network is evaluated once at [`PROBE_POINTS`] temperatures across
//! the calibrated range: bias values must be finite and within ±[`BIAS_MAX_RADS`] rad/s, and
//! every derivative (and derivative-network value) finite, so finite weights that overflow or
//! give absurd biases are refused at load, not turned into NaN later.
//!
//! Deliberately wider than Python: a network may have one or two hidden layers and any of the
//! activations of [`Activation::from_name`] (tanh, logistic, linear), so hand-made or firmware
//! networks load here; Python writes and reads only the 1-n-n-1 tanh/tanh/linear layout.
// No unchecked indexing in library code; a proven index carries an `allow`.
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]
use super::{Activation, Affine, LayerSpec, Mlp};
use serde::Deserialize;
use serde_json::{Map, Value};
use std::collections::BTreeSet;
use std::string::{String, ToString};
use std::vec::Vec;
use std::{fmt, format};

/// The `format` field every thermal-model file carries.
pub const FORMAT: &str = "uasnav.thermal-model";
/// The schema version this loader reads.
pub const SCHEMA_VERSION: u32 = 1;
/// Lowest accepted calibrated temperature (°C), as Python's `TEMP_MIN_C`.
pub const TEMP_MIN_C: f64 = -100.0;
/// Highest accepted calibrated temperature (°C), as Python's `TEMP_MAX_C`.
pub const TEMP_MAX_C: f64 = 200.0;
/// Largest |bias| (rad/s) a bias network may give inside its calibrated range, as Python's
/// `BIAS_MAX_RADS`.
pub const BIAS_MAX_RADS: f64 = 100.0;
/// Most axes (networks per list) a model file may hold, as Python's `MAX_AXES`.
pub const MAX_AXES: usize = 64;
/// Temperatures, evenly spaced over the calibrated range (ends included), at which a loaded
/// file's networks are evaluated once (as Python's load-time probe).
pub const PROBE_POINTS: usize = 257;
/// The top-level keys of a model file.
const TOP_KEYS: [&str; 11] = [
    "format",
    "schema_version",
    "kind",
    "quantity",
    "axes",
    "units",
    "calibrated_range_c",
    "models",
    "derivative_models",
    "training",
    "checksum",
];

/// A model file that could not be loaded, with a message naming the part at fault.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ModelFileError(pub String);

impl fmt::Display for ModelFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "thermal model file: {}", self.0)
    }
}

impl std::error::Error for ModelFileError {}

/// The error for the value at the JSON path `path`.
fn fail(path: &str, problem: impl fmt::Display) -> ModelFileError {
    ModelFileError(format!("{path}: {problem}"))
}

/// `v` as the file spells it (compact JSON), shortened to about `limit` characters.
fn show(v: &Value, limit: usize) -> String {
    let s = v.to_string();
    if s.chars().count() <= limit {
        return s;
    }
    let mut t: String = s.chars().take(limit.saturating_sub(1)).collect();
    t.push('…');
    t
}

/// `x` for a message: up to 4 decimals below 10⁶, else scientific.
fn num(x: f64) -> String {
    if x.abs() < 1e6 {
        format!("{}", (x * 1e4).round() / 1e4)
    } else {
        format!("{x:.3e}")
    }
}

/// `v` deserialised as `T`, or an error naming `path` (serde's message says what is wrong).
fn typed<'a, T: Deserialize<'a>>(v: &'a Value, path: &str) -> Result<T, ModelFileError> {
    T::deserialize(v).map_err(|e| fail(path, e))
}

/// `d[key]`, or an error naming the missing key.
fn field<'a>(d: &'a Map<String, Value>, key: &str) -> Result<&'a Value, ModelFileError> {
    d.get(key).ok_or_else(|| fail(key, "missing"))
}

/// `v` if it is a JSON string.
fn string<'a>(v: &'a Value, path: &str) -> Result<&'a str, ModelFileError> {
    v.as_str()
        .ok_or_else(|| fail(path, format!("expected a string, got {}", show(v, 40))))
}

/// `v` if it is a JSON array of 1…[`MAX_AXES`] entries.
fn axis_array<'a>(v: &'a Value, path: &str) -> Result<&'a [Value], ModelFileError> {
    let a = v
        .as_array()
        .ok_or_else(|| fail(path, format!("expected an array, got {}", show(v, 40))))?;
    if a.is_empty() {
        return Err(fail(path, "empty array"));
    }
    if a.len() > MAX_AXES {
        return Err(fail(
            path,
            format!("{} entries, at most {MAX_AXES} accepted", a.len()),
        ));
    }
    Ok(a)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Norm {
    offset: f64,
    scale: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LayerJson {
    activation: String,
    weights: Vec<Vec<f64>>,
    biases: Vec<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NetJson {
    input_norm: Value,
    output_norm: Value,
    layers: Vec<Value>,
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

/// A normalisation `{"offset": finite, "scale": finite > 0}` at `path`.
fn norm_from_json(v: &Value, path: &str) -> Result<Affine<f64>, ModelFileError> {
    let n: Norm = typed(v, path)?;
    if !n.offset.is_finite() {
        return Err(fail(
            &format!("{path}.offset"),
            format!("expected a finite number, got {}", n.offset),
        ));
    }
    if !(n.scale.is_finite() && n.scale > 0.0) {
        return Err(fail(
            &format!("{path}.scale"),
            format!("expected a finite number > 0, got {}", n.scale),
        ));
    }
    Ok(Affine {
        offset: n.offset,
        scale: n.scale,
    })
}

fn net_from_json(v: &Value, range: (f64, f64), where_: &str) -> Result<Mlp<f64>, ModelFileError> {
    let n: NetJson = typed(v, where_)?;
    let input = norm_from_json(&n.input_norm, &format!("{where_}.input_norm"))?;
    let output = norm_from_json(&n.output_norm, &format!("{where_}.output_norm"))?;
    if !(2..=3).contains(&n.layers.len()) {
        return Err(fail(
            &format!("{where_}.layers"),
            format!(
                "expected 2 or 3 layers (1 or 2 hidden layers, then the output layer), got {}",
                n.layers.len()
            ),
        ));
    }
    let mut layers: Vec<LayerJson> = Vec::with_capacity(n.layers.len());
    let mut flat: Vec<Vec<f64>> = Vec::with_capacity(n.layers.len());
    let mut acts = Vec::with_capacity(n.layers.len());
    let mut fan_in = 1usize;
    for (i, lv) in n.layers.iter().enumerate() {
        let q = format!("{where_}.layers[{i}]");
        let l: LayerJson = typed(lv, &q)?;
        if l.weights.len() != l.biases.len() {
            return Err(fail(
                &format!("{q}.weights"),
                format!(
                    "{} weight rows but {} biases",
                    l.weights.len(),
                    l.biases.len()
                ),
            ));
        }
        if let Some((r, row)) = l
            .weights
            .iter()
            .enumerate()
            .find(|(_, w)| w.len() != fan_in)
        {
            return Err(fail(
                &format!("{q}.weights[{r}]"),
                format!(
                    "weight row {r} has {} entries, expected {fan_in}",
                    row.len()
                ),
            ));
        }
        acts.push(Activation::from_name(&l.activation).map_err(|_| {
            fail(
                &format!("{q}.activation"),
                format!(
                    "unknown activation {:?} (expected tanh, logistic or linear)",
                    l.activation
                ),
            )
        })?);
        fan_in = l.biases.len();
        flat.push(l.weights.iter().flatten().copied().collect());
        layers.push(l);
    }
    let specs: Vec<LayerSpec<'_, f64>> = layers
        .iter()
        .zip(flat.iter())
        .zip(acts.iter())
        .map(|((l, w), a)| LayerSpec {
            weights: w,
            biases: &l.biases,
            activation: *a,
        })
        .collect();
    Mlp::new(&specs, input, output, range).map_err(|e| fail(where_, e))
}

/// SHA-256 (lower-case hex) of `text` with the one occurrence of `value` replaced by 64 `0`s.
pub fn file_checksum(text: &str, value: &str) -> String {
    use sha2::{Digest, Sha256};
    let zeros = "0".repeat(64);
    let digest = Sha256::digest(text.replacen(value, &zeros, 1).as_bytes());
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// Verifies the `checksum` object of the file `text`.
fn verify_checksum(text: &str, checksum: Option<&Value>) -> Result<(), ModelFileError> {
    let c = checksum.and_then(Value::as_object);
    let algorithm = c.and_then(|c| c.get("algorithm")).and_then(Value::as_str);
    let value = c.and_then(|c| c.get("value")).and_then(Value::as_str);
    let value = match (algorithm, value) {
        (Some("sha256"), Some(value)) => value,
        (Some(a), _) if a != "sha256" => {
            return Err(ModelFileError(format!(
                "checksum algorithm {a:?} is not supported (expected \"sha256\")"
            )))
        }
        _ => return Err(fail("checksum", "missing or malformed (expected an object with \"algorithm\": \"sha256\" and a hex \"value\")")),
    };
    let is_hex = value.len() == 64 && value.bytes().all(|b| b.is_ascii_hexdigit());
    if !is_hex || text.matches(value).count() != 1 {
        return Err(ModelFileError(
            "checksum value is not a unique 64-digit hex string".to_string(),
        ));
    }
    let got = file_checksum(text, value);
    if got != value {
        return Err(ModelFileError(format!(
            "checksum mismatch (file edited or corrupted): expected {value}, got {got}"
        )));
    }
    Ok(())
}

/// Checksum, format and schema version (an edited file is refused as such), then no unknown
/// key, `kind`, `quantity` and `units`.
fn check_header(text: &str, d: &Map<String, Value>) -> Result<(), ModelFileError> {
    verify_checksum(text, d.get("checksum"))?;
    let format = d.get("format");
    if format.and_then(Value::as_str) != Some(FORMAT) {
        return Err(ModelFileError(format!(
            "format is {}, expected {FORMAT:?}",
            format.map_or_else(|| "missing".to_string(), |v| show(v, 40))
        )));
    }
    match d.get("schema_version") {
        None => return Err(fail("schema_version", "missing")),
        Some(v) if v.as_u64() != Some(u64::from(SCHEMA_VERSION)) => {
            return Err(ModelFileError(format!(
                "schema_version {} is not supported (this build reads {SCHEMA_VERSION})",
                show(v, 20)
            )))
        }
        Some(_) => {}
    }
    if let Some(k) = d.keys().find(|k| !TOP_KEYS.contains(&k.as_str())) {
        return Err(fail(
            k,
            format!("unknown key (known: {})", TOP_KEYS.join(", ")),
        ));
    }
    let kind = string(field(d, "kind")?, "kind")?;
    if kind != "neural" {
        return Err(ModelFileError(format!(
            "kind {kind:?} holds no network (the Rust engine evaluates kind \"neural\")"
        )));
    }
    let quantity = field(d, "quantity")?;
    if string(quantity, "quantity")? != "gyro_bias" {
        return Err(fail(
            "quantity",
            format!("expected \"gyro_bias\", got {}", show(quantity, 40)),
        ));
    }
    let units = field(d, "units")?;
    let expected =
        serde_json::json!({"input": "degC", "output": "rad/s", "derivative": "rad/s/degC"});
    if *units != expected {
        return Err(fail(
            "units",
            format!("{}, expected {expected}", show(units, 120)),
        ));
    }
    Ok(())
}

/// `calibrated_range_c`: two finite numbers within [`TEMP_MIN_C`, `TEMP_MAX_C`], min < max.
fn calibrated_range(v: &Value) -> Result<(f64, f64), ModelFileError> {
    const KEY: &str = "calibrated_range_c";
    let (a, b) = match v.as_array().map(Vec::as_slice) {
        Some([a, b]) => (a, b),
        _ => {
            return Err(fail(
                KEY,
                format!(
                    "expected [min, max] as an array of two numbers, got {}",
                    show(v, 40)
                ),
            ))
        }
    };
    let end = |i: usize, x: &Value| -> Result<f64, ModelFileError> {
        let path = format!("{KEY}[{i}]");
        let t = x
            .as_f64()
            .ok_or_else(|| fail(&path, format!("expected a number, got {}", show(x, 40))))?;
        if !t.is_finite() {
            return Err(fail(&path, format!("expected a finite number, got {t}")));
        }
        if !(TEMP_MIN_C..=TEMP_MAX_C).contains(&t) {
            return Err(fail(
                &path,
                format!(
                    "{} °C is outside the accepted range [{TEMP_MIN_C}, {TEMP_MAX_C}] °C",
                    show(x, 40)
                ),
            ));
        }
        Ok(t)
    };
    let (lo, hi) = (end(0, a)?, end(1, b)?);
    if lo >= hi {
        return Err(fail(
            KEY,
            format!(
                "minimum {} is not below maximum {}",
                show(a, 40),
                show(b, 40)
            ),
        ));
    }
    Ok((lo, hi))
}

/// `axes`: as many distinct strings as there are `models` (`k`).
fn check_axes(v: &Value, k: usize) -> Result<(), ModelFileError> {
    let axes = axis_array(v, "axes")?;
    let names = axes
        .iter()
        .enumerate()
        .map(|(i, a)| string(a, &format!("axes[{i}]")))
        .collect::<Result<Vec<_>, _>>()?;
    if names.len() != k {
        return Err(fail(
            "axes",
            format!(
                "{} axes named but {k} models given (one model per axis)",
                names.len()
            ),
        ));
    }
    let mut seen = BTreeSet::new();
    if let Some(name) = names.iter().find(|n| !seen.insert(**n)) {
        return Err(fail("axes", format!("axis name {name:?} repeats")));
    }
    Ok(())
}

/// The [`PROBE_POINTS`] temperatures of the load-time probe: evenly spaced over `range`, ends
/// included (as NumPy's `linspace`).
fn probe_temperatures(range: (f64, f64)) -> impl Iterator<Item = f64> {
    let (lo, hi) = range;
    let last = PROBE_POINTS - 1;
    let step = (hi - lo) / last as f64;
    (0..PROBE_POINTS).map(move |i| if i == last { hi } else { i as f64 * step + lo })
}

/// Evaluates `nets` (the list `key`) once over the calibrated range: each value must be finite
/// and within ±`limit` rad/s, each derivative finite (`what`: the names of both in messages).
/// The first failure (lowest temperature, then lowest index; values before derivatives) is
/// reported.
fn probe(
    nets: &[Mlp<f64>],
    range: (f64, f64),
    key: &str,
    what: (&str, &str),
    limit: f64,
) -> Result<(), ModelFileError> {
    let checks = [(false, what.0, limit), (true, what.1, f64::INFINITY)];
    for (derivative, name, limit) in checks {
        for t in probe_temperatures(range) {
            for (j, net) in nets.iter().enumerate() {
                let o = net.eval(t);
                let x = if derivative { o.derivative } else { o.value };
                if !x.is_finite() || x.abs() > limit {
                    let shown = if x.is_finite() {
                        format!("{} rad/s, beyond ±{} rad/s", num(x), num(limit))
                    } else {
                        "non-finite".to_string()
                    };
                    return Err(fail(
                        &format!("{key}[{j}]"),
                        format!("the model's {name} at {} °C is {shown}", num(t)),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Parses a thermal-model file's text into its networks, validated fully (see the module
/// documentation): checksum first, then every key, then the networks evaluated once over the
/// calibrated range. Every error names the JSON key at fault.
pub fn load_thermal_model(text: &str) -> Result<ThermalNetworks, ModelFileError> {
    let v: Value = serde_json::from_str(text)
        .map_err(|e| ModelFileError(format!("not a valid model file: {e}")))?;
    let d = v.as_object().ok_or_else(|| {
        ModelFileError("not a valid model file: expected a JSON object at the top level".into())
    })?;
    check_header(text, d)?;
    let range = calibrated_range(field(d, "calibrated_range_c")?)?;
    let models = axis_array(field(d, "models")?, "models")?;
    let k = models.len();
    check_axes(field(d, "axes")?, k)?;
    let derivative_models = match d.get("derivative_models") {
        None | Some(Value::Null) => None,
        Some(dm) => {
            let list = axis_array(dm, "derivative_models")?;
            if list.len() != k {
                return Err(fail(
                    "derivative_models",
                    format!(
                        "{} networks for {k} axes (one per axis, or null)",
                        list.len()
                    ),
                ));
            }
            Some(list)
        }
    };
    if let Some(t) = d.get("training") {
        if !t.is_object() {
            return Err(fail(
                "training",
                format!("expected an object, got {}", show(t, 40)),
            ));
        }
    }
    let bias = models
        .iter()
        .enumerate()
        .map(|(i, v)| net_from_json(v, range, &format!("models[{i}]")))
        .collect::<Result<Vec<_>, _>>()?;
    let derivative = match derivative_models {
        None => None,
        Some(list) => Some(
            list.iter()
                .enumerate()
                .map(|(i, v)| net_from_json(v, range, &format!("derivative_models[{i}]")))
                .collect::<Result<Vec<_>, _>>()?,
        ),
    };
    probe(
        &bias,
        range,
        "models",
        ("bias", "bias derivative"),
        BIAS_MAX_RADS,
    )?;
    if let Some(nets) = &derivative {
        probe(
            nets,
            range,
            "derivative_models",
            ("∂b/∂T", "derivative of ∂b/∂T"),
            f64::INFINITY,
        )?;
    }
    Ok(ThermalNetworks {
        bias,
        derivative,
        range_c: range,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    const GOOD: &str = r#"{"format": "uasnav.thermal-model", "schema_version": 1, "kind": "neural",
      "quantity": "gyro_bias", "axes": ["x"],
      "units": {"input": "degC", "output": "rad/s", "derivative": "rad/s/degC"},
      "calibrated_range_c": [-20.0, 40.0],
      "models": [{"input_norm": {"offset": 10.0, "scale": 0.05},
                  "output_norm": {"offset": 0.001, "scale": 0.0002},
                  "layers": [{"activation": "tanh", "weights": [[0.8], [-1.3]], "biases": [0.1, 0.4]},
                             {"activation": "tanh", "weights": [[0.5, -0.7], [1.1, 0.3]], "biases": [-0.2, 0.05]},
                             {"activation": "linear", "weights": [[1.5, -0.6]], "biases": [0.02]}]}],
      "derivative_models": null, "training": {"anything": 1},
      "checksum": {"algorithm": "sha256", "value": "0000000000000000000000000000000000000000000000000000000000000000"}}"#;

    /// A file exactly as Python wrote it (`uasnav.thermal.dumps_model` of a 1-2-2-1 network
    /// fitted on two axes, with derivative networks).
    const PYTHON_FILE: &str = r#"{
 "format": "uasnav.thermal-model",
 "schema_version": 1,
 "kind": "neural",
 "quantity": "gyro_bias",
 "axes": [
  "x",
  "y"
 ],
 "units": {
  "input": "degC",
  "output": "rad/s",
  "derivative": "rad/s/degC"
 },
 "calibrated_range_c": [
  -10.0,
  40.0
 ],
 "models": [
  {
   "input_norm": {
    "offset": 15.0,
    "scale": 0.04
   },
   "output_norm": {
    "offset": -6.938893903907229e-20,
    "scale": 0.0007786364289240974
   },
   "layers": [
    {
     "activation": "tanh",
     "weights": [
      [
       -1.096088498456409
      ],
      [
       2.3511889555461862
      ]
     ],
     "biases": [
      -1.8278579647124387,
      0.10724767440815783
     ]
    },
    {
     "activation": "tanh",
     "weights": [
      [
       -0.007786602371614869,
       -1.0927439382452873
      ],
      [
       0.027369654010215246,
       -0.8264336247550467
      ]
     ],
     "biases": [
      -0.7598364045553454,
      0.6340409488329032
     ]
    },
    {
     "activation": "linear",
     "weights": [
      [
       -0.5829197572732447,
       -1.6485614304670138
      ]
     ],
     "biases": [
      0.3777157049448191
     ]
    }
   ]
  },
  {
   "input_norm": {
    "offset": 15.0,
    "scale": 0.04
   },
   "output_norm": {
    "offset": 2.4973676643697276e-05,
    "scale": 0.00013064650888162425
   },
   "layers": [
    {
     "activation": "tanh",
     "weights": [
      [
       2.275320938247441
      ],
      [
       -0.9888674853093111
      ]
     ],
     "biases": [
      -1.2242272410557224,
      -0.537037594941333
     ]
    },
    {
     "activation": "tanh",
     "weights": [
      [
       -0.8713645642759754,
       -1.657552240244419
      ],
      [
       -1.2203017998665384,
       1.7910767084903385
      ]
     ],
     "biases": [
      -0.8881504104398859,
      0.21190598621341195
     ]
    },
    {
     "activation": "linear",
     "weights": [
      [
       2.8981256334868175,
       0.8718773571400684
      ]
     ],
     "biases": [
      -0.6418886958701606
     ]
    }
   ]
  }
 ],
 "derivative_models": [
  {
   "input_norm": {
    "offset": 15.0,
    "scale": 0.04
   },
   "output_norm": {
    "offset": 3.938056988913725e-05,
    "scale": 3.316176135769816e-05
   },
   "layers": [
    {
     "activation": "tanh",
     "weights": [
      [
       2.221382320660097
      ],
      [
       2.4466563346384165
      ]
     ],
     "biases": [
      -0.3271607124275036,
      0.35885118302669083
     ]
    },
    {
     "activation": "tanh",
     "weights": [
      [
       -0.09869102934361944,
       0.9687787893660627
      ],
      [
       -1.5142783381719347,
       1.3737675026642848
      ]
     ],
     "biases": [
      1.1450521608867366,
      -0.8426964915948559
     ]
    },
    {
     "activation": "linear",
     "weights": [
      [
       0.7134108724460904,
       3.5082421310850385
      ]
     ],
     "biases": [
      0.7716426150064836
     ]
    }
   ]
  },
  {
   "input_norm": {
    "offset": 15.0,
    "scale": 0.04
   },
   "output_norm": {
    "offset": -2.6818977639671964e-07,
    "scale": 1.6577564650979027e-05
   },
   "layers": [
    {
     "activation": "tanh",
     "weights": [
      [
       -1.7165078647171927
      ],
      [
       3.085736897500218
      ]
     ],
     "biases": [
      1.1441316656700686,
      1.6693050203566673
     ]
    },
    {
     "activation": "tanh",
     "weights": [
      [
       -1.8960228256251614,
       2.3841778476254194
      ],
      [
       -0.9652405762248358,
       0.42612953767420414
      ]
     ],
     "biases": [
      -0.836709614832884,
      -0.6377273207703504
     ]
    },
    {
     "activation": "linear",
     "weights": [
      [
       -1.931433641904096,
       1.7667721137908072
      ]
     ],
     "biases": [
      0.9255858096532129
     ]
    }
   ]
  }
 ],
 "training": {
  "created_utc": "2026-11-23T19:30:25+00:00",
  "source": "rust-parity-fixture",
  "networks": [
   {
    "epochs": 20,
    "stop": "max_epochs",
    "train_mse": 5.411814000784221e-07,
    "val_mse": 5.08396721458271e-07,
    "test_mse": 5.491655908257671e-07,
    "restarts": 1,
    "seconds": 0.009113869999964663
   },
   {
    "epochs": 20,
    "stop": "max_epochs",
    "train_mse": 1.2284361476360003e-05,
    "val_mse": 1.2491992717355154e-05,
    "test_mse": 1.37858264014675e-05,
    "restarts": 1,
    "seconds": 0.008321074000377848
   }
  ]
 },
 "checksum": {
  "algorithm": "sha256",
  "value": "98e7b8bc56859eaf3eb02fadc1739dd5dc86962dcc09201cfb600c09377e0773"
 }
}
"#;

    /// Signs a test file: its checksum is computed over the zero placeholder.
    fn signed(text: &str) -> String {
        let zeros = "0".repeat(64);
        let c = file_checksum(text, &zeros);
        text.replacen(&zeros, &c, 1)
    }

    /// GOOD with two axes and derivative networks, as a value to edit.
    fn base() -> Value {
        let mut d: Value = serde_json::from_str(GOOD).unwrap();
        let net = d["models"][0].clone();
        d["models"] = json!([net.clone(), net.clone()]);
        d["axes"] = json!(["x", "y"]);
        d["derivative_models"] = json!([net.clone(), net]);
        d
    }

    /// `d` as a signed file.
    fn sign_value(d: &Value) -> String {
        let mut d = d.clone();
        d["checksum"] = json!({"algorithm": "sha256", "value": "0".repeat(64)});
        signed(&serde_json::to_string_pretty(&d).unwrap())
    }

    /// `base()` with the value at the JSON pointer `ptr` replaced (or added), or removed
    /// (`None`), signed.
    fn with(ptr: &str, new: Option<Value>) -> String {
        let mut d = base();
        let (parent, key) = ptr.rsplit_once('/').unwrap();
        match (d.pointer_mut(parent).unwrap(), new) {
            (Value::Object(m), Some(v)) => {
                m.insert(key.to_string(), v);
            }
            (Value::Object(m), None) => {
                m.remove(key);
            }
            (Value::Array(a), Some(v)) => a[key.parse::<usize>().unwrap()] = v,
            (Value::Array(a), None) => {
                a.remove(key.parse::<usize>().unwrap());
            }
            _ => panic!("{ptr}: parent is not a container"),
        }
        sign_value(&d)
    }

    fn refused(text: &str) -> String {
        match load_thermal_model(text) {
            Ok(_) => panic!("accepted a hostile file:\n{text}"),
            Err(e) => e.to_string(),
        }
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
        // The edited base (two axes, derivative networks) is valid: the cases below can fail.
        let b = load_thermal_model(&sign_value(&base())).unwrap();
        assert_eq!((b.bias.len(), b.derivative.map(|d| d.len())), (2, Some(2)));
    }

    #[test]
    fn python_written_file_loads_with_unchanged_outputs() {
        let t = load_thermal_model(PYTHON_FILE).unwrap();
        assert_eq!(t.range_c, (-10.0, 40.0));
        let derivative = t.derivative.as_deref().unwrap();
        assert_eq!((t.bias.len(), derivative.len()), (2, 2));
        // Outputs of the loader before full validation was added (bit-exact).
        let temps = [-10.0, 0.0, 15.5, 40.0];
        const VALUE: [[f64; 2]; 4] = [
            [-0.0009869419828253993, -0.00018143057787144384],
            [-0.0009047798740329601, -5.174893269761574e-07],
            [4.915467752377923e-05, 0.00019754787021690836],
            [0.0009878726624564706, -0.0001942168446643922],
        ];
        let value = VALUE;
        const SLOPE: [[f64; 2]; 4] = [
            [2.8783566460318373e-06, 1.2222610192105007e-05],
            [1.7894355555514764e-05, 2.22818327759241e-05],
            [9.959418718949254e-05, -3.1612887691629856e-06],
            [2.907828162185707e-06, -7.561598448219897e-06],
        ];
        let slope = SLOPE;
        const DNET: [[f64; 2]; 4] = [
            [3.185917429869945e-06, 1.890709888048746e-05],
            [1.790822078723213e-05, 1.9742607525067673e-05],
            [9.880019106194203e-05, -3.5106045703738843e-06],
            [3.0069885195322735e-06, -8.341884771453436e-06],
        ];
        let dnet = DNET;
        for (i, &x) in temps.iter().enumerate() {
            for k in 0..2 {
                let o = t.bias[k].eval_clipped(x).unwrap();
                assert_eq!(o.value.to_bits(), value[i][k].to_bits(), "value {x} {k}");
                assert_eq!(
                    o.derivative.to_bits(),
                    slope[i][k].to_bits(),
                    "slope {x} {k}"
                );
                let od = derivative[k].eval_clipped(x).unwrap();
                assert_eq!(od.value.to_bits(), dnet[i][k].to_bits(), "dnet {x} {k}");
            }
        }
    }

    #[test]
    fn one_hidden_layer_is_accepted() {
        // Wider than Python on purpose (module doc): a 1-n-1 network loads.
        let text = with(
            "/models/1/layers",
            Some(json!([
                {"activation": "tanh", "weights": [[0.8], [-1.3]], "biases": [0.1, 0.4]},
                {"activation": "linear", "weights": [[1.5, -0.6]], "biases": [0.02]}
            ])),
        );
        let t = load_thermal_model(&text).unwrap();
        assert_eq!(t.bias[1].hidden_sizes(), (2, 2));
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
            (
                edit("\"schema_version\": 1", "\"schema_version\": \"1\""),
                "schema_version \"1\" is not supported",
            ),
            (edit("uasnav.thermal-model", "other"), "format"),
            (
                edit("\"kind\": \"neural\"", "\"kind\": \"polynomial\""),
                "kind",
            ),
            (
                edit("\"kind\": \"neural\"", "\"kind\": 3"),
                "kind: expected a string",
            ),
            (
                edit("\"output\": \"rad/s\"", "\"output\": \"deg/s\""),
                "units",
            ),
            (
                edit("[[0.5, -0.7], [1.1, 0.3]]", "[[0.5], [1.1, 0.3]]"),
                "models[0].layers[1].weights[0]: weight row 0",
            ),
            (
                edit("\"tanh\"", "\"relu\""),
                "models[0].layers[0].activation",
            ),
            (good[..200].to_string(), "not a valid model file"),
            (good.replace("0.8", "0.9"), "checksum mismatch"),
            (GOOD.to_string(), "checksum mismatch"),
            (good.replace("\"sha256\"", "\"md5\""), "algorithm"),
            ("[1, 2]".to_string(), "expected a JSON object"),
            // JSON holds no non-finite number: NaN or an overflowing literal is not JSON.
            (
                edit("\"scale\": 0.05", "\"scale\": 1e999"),
                "not a valid model file",
            ),
            (
                edit("\"scale\": 0.05", "\"scale\": NaN"),
                "not a valid model file",
            ),
        ];
        for (text, needle) in cases {
            let e = refused(&text);
            assert!(e.contains(needle), "{e} should mention {needle}");
        }
    }

    #[test]
    fn refuses_hostile_files_naming_the_key() {
        let many: Vec<Value> = (0..65).map(|_| base()["models"][0].clone()).collect();
        let huge_out = json!({"offset": 0.0, "scale": 1e300});
        let cases: Vec<(String, &str)> = vec![
            // Normalisation scales must be > 0.
            (
                with("/models/0/input_norm/scale", Some(json!(0.0))),
                "models[0].input_norm.scale: expected a finite number > 0, got 0",
            ),
            (
                with("/models/1/input_norm/scale", Some(json!(-0.04))),
                "models[1].input_norm.scale: expected a finite number > 0, got -0.04",
            ),
            (
                with("/models/1/output_norm/scale", Some(json!(-2e-4))),
                "models[1].output_norm.scale",
            ),
            (
                with("/derivative_models/1/output_norm/scale", Some(json!(0))),
                "derivative_models[1].output_norm.scale",
            ),
            (
                with("/models/0/input_norm/offset", Some(json!("10"))),
                "models[0].input_norm: invalid type: string",
            ),
            // The calibrated range.
            (
                with("/calibrated_range_c", Some(json!([40.0, -20.0]))),
                "calibrated_range_c: minimum 40.0 is not below maximum -20.0",
            ),
            (
                with("/calibrated_range_c", Some(json!([10.0, 10.0]))),
                "calibrated_range_c: minimum",
            ),
            (
                with("/calibrated_range_c", Some(json!([27.0, 1e308]))),
                "calibrated_range_c[1]: 1e+308 °C is outside the accepted range [-100, 200] °C",
            ),
            (
                with("/calibrated_range_c", Some(json!([-273.15, 40.0]))),
                "calibrated_range_c[0]",
            ),
            (
                with("/calibrated_range_c", Some(json!("27..34"))),
                "calibrated_range_c: expected [min, max]",
            ),
            (
                with("/calibrated_range_c", Some(json!(["27", 34]))),
                "calibrated_range_c[0]: expected a number, got \"27\"",
            ),
            (
                with("/calibrated_range_c", Some(json!([1.0, 2.0, 3.0]))),
                "calibrated_range_c: expected [min, max]",
            ),
            (
                with("/calibrated_range_c", None),
                "calibrated_range_c: missing",
            ),
            // Axes: one distinct name per model.
            (
                with("/axes", Some(json!(["x"]))),
                "axes: 1 axes named but 2 models given",
            ),
            (
                with("/axes", Some(json!(["x", "y", "z"]))),
                "axes: 3 axes named but 2 models given",
            ),
            (
                with("/axes", Some(json!(["x", "x"]))),
                "axes: axis name \"x\" repeats",
            ),
            (
                with("/axes", Some(json!(["x", 1]))),
                "axes[1]: expected a string, got 1",
            ),
            (with("/axes", Some(json!("xy"))), "axes: expected an array"),
            (with("/axes", Some(json!([]))), "axes: empty array"),
            (with("/axes", None), "axes: missing"),
            // Derivative networks: one per axis, or null; at most 64 models.
            (
                with("/derivative_models/1", None),
                "derivative_models: 1 networks for 2 axes",
            ),
            (
                with("/derivative_models", Some(json!([]))),
                "derivative_models: empty array",
            ),
            (
                with("/derivative_models", Some(json!({}))),
                "derivative_models: expected an array",
            ),
            (
                with("/models", Some(Value::Array(many))),
                "models: 65 entries, at most 64 accepted",
            ),
            (with("/models", Some(json!([]))), "models: empty array"),
            // Top-level keys, quantity, training.
            (with("/extra", Some(json!(1))), "extra: unknown key"),
            (
                with("/quantity", Some(json!("accel_bias"))),
                "quantity: expected \"gyro_bias\", got \"accel_bias\"",
            ),
            (
                with("/quantity", Some(json!(null))),
                "quantity: expected a string",
            ),
            (with("/quantity", None), "quantity: missing"),
            (
                with("/training", Some(json!([1, 2]))),
                "training: expected an object",
            ),
            (
                with("/training", Some(json!(null))),
                "training: expected an object",
            ),
            (with("/units/derivative", Some(json!("rad/s/K"))), "units: "),
            (
                // Not signed: sign_value would add the checksum back.
                {
                    let mut d = base();
                    d.as_object_mut().unwrap().remove("checksum");
                    serde_json::to_string(&d).unwrap()
                },
                "checksum: missing",
            ),
            // Unknown keys inside a network.
            (
                with("/models/0/extra", Some(json!(1))),
                "models[0]: unknown field `extra`",
            ),
            (
                with("/models/1/input_norm/gain", Some(json!(1))),
                "models[1].input_norm: unknown field `gain`",
            ),
            (
                with("/derivative_models/0/layers/2/bias", Some(json!(1))),
                "derivative_models[0].layers[2]: unknown field `bias`",
            ),
            (
                with(
                    "/models/0/layers/1/weights",
                    Some(json!([[[0.5, -0.7]], [1.1, 0.3]])),
                ),
                "models[0].layers[1]: invalid type: sequence, expected f64",
            ),
            (
                with("/models/0/layers", Some(json!([]))),
                "models[0].layers: expected 2 or 3 layers",
            ),
            // Finite weights that give absurd or non-finite outputs: the probe.
            (
                with("/models/1/layers/2/weights/0/0", Some(json!(1e300))),
                "models[1]: the model's bias at -20 °C is",
            ),
            (
                with("/models/0/output_norm/offset", Some(json!(150.0))),
                "models[0]: the model's bias at -20 °C is 149.9998 rad/s, beyond ±100 rad/s",
            ),
            (
                with("/models/1/output_norm", Some(huge_out.clone())),
                "models[1]: the model's bias at -20 °C is",
            ),
            (
                with("/models/0/layers/2/weights/0", Some(json!([1e300, 1e300]))),
                "models[0]: the model's bias at -20 °C is",
            ),
            (
                {
                    // Value finite everywhere, derivative infinite where u = 0.
                    let mut d = base();
                    d["models"][0]["input_norm"] = json!({"offset": -20.0, "scale": 1e308});
                    d["models"][0]["layers"][0]["weights"] = json!([[10.0], [-13.0]]);
                    sign_value(&d)
                },
                "models[0]: the model's bias derivative at -20 °C is non-finite",
            ),
            (
                {
                    let mut d = base();
                    d["derivative_models"][1]["output_norm"] = huge_out;
                    d["derivative_models"][1]["layers"][2]["weights"] = json!([[1e300, 1e300]]);
                    sign_value(&d)
                },
                "derivative_models[1]: the model's ∂b/∂T at -20 °C is non-finite",
            ),
        ];
        for (text, needle) in cases {
            let e = refused(&text);
            assert!(e.contains(needle), "{e:?} should mention {needle:?}");
            assert!(!e.contains('\n'), "{e:?} is more than one line");
        }
    }
}
