//! The study file: its format as serde reads it, and the checks that make a [`Study`] of it.
//! Every problem is one line naming the study file and, where there is one, the parameter.

use std::path::Path;

use serde::Deserialize;

use super::draw::{self, Distribution};
use super::keys::{override_scene_text, value_at};
use super::outcomes::{Outcome, OutcomeSettings, watched};
use super::{MAX_CASES, Parameter, Study, StudyError};
use crate::scene::{ReadError, read_utf8, shorten_numbers};

/// The outcomes of a study file without `outcomes`: the list (#18) of what a rockfall or
/// slope study is judged by.
pub const DEFAULT_OUTCOMES: [&str; 6] = [
    "max_displacement",
    "runout",
    "blocks_moved",
    "peak_normal_force",
    "final_kinetic_energy",
    "max_penetration",
];

fn default_outcomes() -> Vec<String> {
    DEFAULT_OUTCOMES.iter().map(|s| s.to_string()).collect()
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyFile {
    scene: String,
    #[serde(default)]
    seed: u64,
    cases: Option<i64>,
    /// Left out: [`DEFAULT_OUTCOMES`].
    #[serde(default = "default_outcomes")]
    outcomes: Vec<String>,
    #[serde(default)]
    parameters: Vec<ParameterSpec>,
    moved_threshold: Option<f64>,
    toppled_angle: Option<f64>,
    watch: Option<Vec<String>>,
    case_timeout: Option<f64>,
    /// Keys set to one value in every case (not columns of the table).
    #[serde(default)]
    set: toml::Table,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ParameterSpec {
    key: String,
    values: Option<Vec<toml::Value>>,
    uniform: Option<[f64; 2]>,
    log_uniform: Option<[f64; 2]>,
    normal: Option<[f64; 2]>,
    bounds: Option<[f64; 2]>,
}

impl ParameterSpec {
    fn distribution(&self) -> Result<Distribution, String> {
        let given: Vec<&str> = [
            ("values", self.values.is_some()),
            ("uniform", self.uniform.is_some()),
            ("log_uniform", self.log_uniform.is_some()),
            ("normal", self.normal.is_some()),
        ]
        .iter()
        .filter(|(_, set)| *set)
        .map(|(n, _)| *n)
        .collect();
        if given.len() != 1 {
            return Err(format!(
                "give exactly one of values, uniform, log_uniform, normal (got {})",
                if given.is_empty() {
                    "none".into()
                } else {
                    given.join(" and ")
                }
            ));
        }
        if self.bounds.is_some() && self.normal.is_none() {
            return Err("bounds go with normal only".into());
        }
        let d = if let Some(v) = &self.values {
            Distribution::Values(v.clone())
        } else if let Some([lo, hi]) = self.uniform {
            Distribution::Uniform { lo, hi }
        } else if let Some([lo, hi]) = self.log_uniform {
            Distribution::LogUniform { lo, hi }
        } else {
            let [mean, sd] = self.normal.unwrap_or_default();
            Distribution::Normal {
                mean,
                sd,
                bounds: self.bounds,
            }
        };
        d.check()?;
        Ok(d)
    }
}

/// A hash of the texts (FNV-1a, 64 bits), in hex: stable across builds and platforms.
fn fingerprint(texts: &[&str]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for t in texts {
        for &b in t.as_bytes().iter().chain(&[0u8]) {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    format!("{h:016x}")
}

/// A study's scene's text, read no further than a scene file may be (`study /dev/zero` read
/// until memory ran out). A failure to read names the scene: the line names the study file.
fn read(path: &Path, kind: &str) -> Result<String, String> {
    read_utf8(path, kind).map_err(|e| match e {
        ReadError::Io(e) => format!("cannot read {}: {e}", path.display()),
        other => other.to_string(),
    })
}

/// Reads and checks a study file and its base scene.
pub(super) fn load(path: &Path) -> Result<Study, StudyError> {
    let shown = path.display().to_string();
    // Numbers short, as a scene file's errors have them (`toppled_angle = 1e300`, not 301
    // digits).
    let fail = |m: String| StudyError::input(format!("{shown}: {}", shorten_numbers(&m)));
    // The study file is named at the start of the line already: not twice.
    let text = read_utf8(path, "a study file").map_err(|e| fail(e.to_string()))?;
    let file: StudyFile = toml::from_str(&text).map_err(|e| {
        let line = e
            .span()
            .map(|s| format!("line {}: ", text[..s.start].matches('\n').count() + 1));
        fail(format!(
            "{}{}",
            line.unwrap_or_default(),
            e.message().trim().replace('\n', " ")
        ))
    })?;
    let scene_path = path.parent().unwrap_or(Path::new("")).join(&file.scene);
    let scene_text = read(&scene_path, "a scene file").map_err(|e| fail(format!("scene: {e}")))?;
    let default_name = scene_path
        .file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    let base = crate::scene::parse(&scene_text, &file.scene, &default_name)
        .map_err(|e| fail(format!("scene: {e}")))?;
    let outcomes = outcomes(&file.outcomes).map_err(fail)?;
    let settings = settings(&file, &base).map_err(fail)?;
    let case_timeout = match file.case_timeout {
        Some(t) if !(t.is_finite() && t > 0.0) => {
            return Err(fail(format!(
                "case_timeout = {t}: must be a positive number of seconds"
            )));
        }
        t => t,
    };
    if file.parameters.is_empty() {
        return Err(fail(
            "no [[parameters]]: a study varies at least one scene key".into(),
        ));
    }
    let fixed: Vec<(String, toml::Value)> = file.set.clone().into_iter().collect();
    for (key, value) in &fixed {
        let text = override_scene_text(&scene_text, &[(key.clone(), value.clone())])
            .map_err(|e| fail(format!("set: {e} in {}", file.scene)))?;
        crate::scene::parse(&text, &file.scene, &default_name)
            .map_err(|e| fail(format!("set: key \"{key}\": {e}")))?;
    }
    let mut parameters: Vec<Parameter> = Vec::new();
    for (i, p) in file.parameters.iter().enumerate() {
        let at = |m: String| fail(format!("parameters[{i}]: key \"{}\": {m}", p.key));
        if parameters.iter().any(|q| q.key == p.key) {
            return Err(at("given twice".into()));
        }
        if fixed.iter().any(|(k, _)| *k == p.key) {
            return Err(at("also in set: a key is either set or varied".into()));
        }
        let dist = p.distribution().map_err(at)?;
        let param = check_key(p, dist, &scene_text, &file.scene, &default_name)
            .map_err(|m| fail(format!("parameters[{i}]: {m}")))?;
        parameters.push(param);
    }
    let dists: Vec<&Distribution> = parameters.iter().map(|p| &p.dist).collect();
    let grid = draw::grid_len(&dists, MAX_CASES).ok_or_else(|| {
        fail(format!(
            "the values lists make a grid of more than {MAX_CASES} cases"
        ))
    })?;
    let draws = if dists.iter().any(|d| d.is_random()) {
        let n = file.cases.ok_or_else(|| {
            fail("cases: missing: give the number of random draws (cases = 100)".into())
        })?;
        if !(1..=MAX_CASES as i64).contains(&n) {
            return Err(fail(format!("cases = {n}: must be 1 to {MAX_CASES}")));
        }
        n as usize
    } else {
        1
    };
    let len = grid
        .checked_mul(draws)
        .filter(|&n| n <= MAX_CASES)
        .ok_or_else(|| {
            fail(format!(
                "{grid} grid points × {draws} cases is more than {MAX_CASES} cases"
            ))
        })?;
    Ok(Study {
        path: path.to_path_buf(),
        scene_written: file.scene.clone(),
        fixed,
        fingerprint: fingerprint(&[&text, &scene_text]),
        scene_text,
        scene_default_name: default_name,
        seed: file.seed,
        draws,
        len,
        parameters,
        outcomes,
        settings,
        case_timeout,
    })
}

/// The outcomes asked for, known and each once.
fn outcomes(names: &[String]) -> Result<Vec<Outcome>, String> {
    if names.is_empty() {
        return Err("outcomes = []: ask for at least one".into());
    }
    let mut out = Vec::new();
    for n in names {
        let o = Outcome::from_name(n).ok_or_else(|| {
            let known: Vec<&str> = Outcome::ALL.iter().map(|o| o.name()).collect();
            format!(
                "outcomes: unknown outcome \"{n}\" (known: {})",
                known.join(", ")
            )
        })?;
        if out.contains(&o) {
            return Err(format!("outcomes: \"{n}\" given twice"));
        }
        out.push(o);
    }
    Ok(out)
}

/// The thresholds and the watched blocks, checked against the base scene.
fn settings(file: &StudyFile, base: &crate::scene::Scene) -> Result<OutcomeSettings, String> {
    let mut s = OutcomeSettings::default();
    if let Some(m) = file.moved_threshold {
        if !(m.is_finite() && m >= 0.0) {
            return Err(format!("moved_threshold = {m}: must be a distance ≥ 0, m"));
        }
        s.moved_threshold = m;
    }
    if let Some(a) = file.toppled_angle {
        if !(a > 0.0 && a < 180.0) {
            return Err(format!(
                "toppled_angle = {a}: must be between 0 and 180 degrees"
            ));
        }
        s.toppled_angle = a;
    }
    let blocks = || base.model.blocks.iter().map(|b| (b.name.as_str(), b.fixed));
    for pattern in file.watch.iter().flatten() {
        let one = OutcomeSettings {
            watch: vec![pattern.clone()],
            ..OutcomeSettings::default()
        };
        if watched(&one, blocks()).is_empty() {
            return Err(format!(
                "watch: \"{pattern}\" matches no free block of {}",
                file.scene
            ));
        }
    }
    s.watch = file.watch.clone().unwrap_or_default();
    Ok(s)
}

/// The parameter, its key checked against the base scene: it can be reached, and the scene
/// parses with the key set to the base's value (or the distribution's typical one). A value
/// list of integers on a float key is taken as floats, so the scene sees the type it reads.
fn check_key(
    p: &ParameterSpec,
    mut dist: Distribution,
    scene_text: &str,
    scene: &str,
    default_name: &str,
) -> Result<Parameter, String> {
    let key = &p.key;
    let base = value_at(scene_text, key).map_err(|e| format!("{e} in {scene}"))?;
    let integer = matches!(base, Some(toml::Value::Integer(_)));
    match &base {
        Some(toml::Value::Float(_)) => {
            if let Distribution::Values(v) = &mut dist {
                for x in v.iter_mut() {
                    if let toml::Value::Integer(i) = *x {
                        *x = toml::Value::Float(i as f64);
                    }
                }
            }
        }
        Some(b @ (toml::Value::String(_) | toml::Value::Boolean(_))) if dist.is_random() => {
            return Err(format!(
                "key \"{key}\": the scene's value is {b}, not a number: vary it with values = [...]"
            ));
        }
        _ => {}
    }
    let probe = base.unwrap_or_else(|| dist.typical());
    let text = override_scene_text(scene_text, &[(key.clone(), probe)])
        .map_err(|e| format!("{e} in {scene}"))?;
    crate::scene::parse(&text, scene, default_name).map_err(|e| format!("key \"{key}\": {e}"))?;
    Ok(Parameter {
        key: key.clone(),
        dist,
        integer,
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn fingerprints_differ_with_either_text() {
        let f = super::fingerprint;
        assert_eq!(f(&["a", "b"]), f(&["a", "b"]));
        assert_ne!(f(&["a", "b"]), f(&["ab", ""]));
        assert_ne!(f(&["a", "b"]), f(&["a", "c"]));
        assert_eq!(f(&["a", "b"]).len(), 16);
    }
}
