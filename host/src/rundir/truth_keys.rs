//! What a `truth.json` says that Plinth does not read: keys it has no field
//! for (a misspelt `k_yy` beside `k_y`, `efects` for `effects`) and effect
//! names it does not know (`probe_runnout`). formats.md lets a format be
//! extended (new keys), and its effect table says the workflow "may know
//! more" names, so neither is an error (a run written by a newer tool stays
//! readable); each is a warning at its line and column, because a misspelt
//! key or name is otherwise lost without a word (its value is not the truth
//! the run is compared with).

use super::Truth;
use crate::effects::EffectKind;
use crate::input_file::{json_key_place, line_column};
use serde_json::Value;
use std::collections::HashMap;

/// Top-level `truth.json` keys Plinth carries without reading them:
/// `source`, where a run came from (free text, e.g. the ROSS script that
/// made it).
pub const CARRIED_KEYS: [&str; 1] = ["source"];

/// One warning per key of `text` (a `truth.json` that parsed as `truth`)
/// that no field of [`Truth`] read, and per `effects` name that is not an
/// [`EffectKind`], each starting with its `line:column: ` [1-based].
///
/// A key is unread when re-writing `truth` does not give it back at the
/// same place (the fields are those of the types, one definition); an
/// absent optional list (`[]`, `null`) is read as empty. The keys expected
/// there are listed beside it.
pub fn unread(text: &str, truth: &Truth) -> Vec<String> {
    let (Ok(input), Ok(reread)) = (
        serde_json::from_str::<Value>(text),
        serde_json::to_value(truth),
    ) else {
        return Vec::new();
    };
    let mut found = Vec::new();
    walk(&input, &reread, "", &mut found);
    let mut nth: HashMap<&str, usize> = HashMap::new();
    let mut notes = Vec::new();
    for (path, key, expected) in &found {
        let n = nth.entry(key.as_str()).or_insert(0);
        *n += 1;
        let place = json_key_place(text, key, *n);
        notes.push((place, format!(
            "key `{key}` ({path}) is not one Plinth reads: ignored (misspelt? expected there: {expected})"
        )));
    }
    let known: Vec<&str> = EffectKind::ALL.iter().map(|e| e.name()).collect();
    let mut seen: HashMap<&str, usize> = HashMap::new();
    for (i, name) in truth.effects.iter().enumerate() {
        let n = seen.entry(name.as_str()).or_insert(0);
        *n += 1;
        if EffectKind::from_name(name).is_some() {
            continue;
        }
        let quoted = format!("\"{name}\"");
        let (line, column) = text
            .match_indices(&quoted)
            .nth(*n - 1)
            .map_or((1, 1), |(at, _)| line_column(text, at));
        notes.push(((line, column), format!(
            "effects[{i}] `{name}` is not an effect Plinth knows (formats.md: {}): a diagnosis is compared with it as written",
            known.join(", ")
        )));
    }
    notes.sort_by_key(|(place, _)| *place);
    notes
        .into_iter()
        .map(|((line, column), note)| format!("{line}:{column}: {note}"))
        .collect()
}

/// Collects (path, key, the keys expected there) for every key of `input`
/// that `reread` lacks at the same place.
fn walk(input: &Value, reread: &Value, path: &str, found: &mut Vec<(String, String, String)>) {
    match (input, reread) {
        (Value::Object(a), Value::Object(b)) => {
            for (key, value) in a {
                let here = if path.is_empty() {
                    key.clone()
                } else {
                    format!("{path}.{key}")
                };
                match b.get(key) {
                    Some(w) => walk(value, w, &here, found),
                    None if empty(value) && path.is_empty() && top_level_keys().contains(key) => {}
                    None if path.is_empty() && CARRIED_KEYS.contains(&key.as_str()) => {}
                    None => {
                        let mut expected: Vec<String> = b.keys().cloned().collect();
                        if path.is_empty() {
                            expected = top_level_keys();
                            expected.extend(CARRIED_KEYS.map(String::from));
                        }
                        found.push((here, key.clone(), expected.join(", ")));
                    }
                }
            }
        }
        (Value::Array(a), Value::Array(b)) => {
            for (i, (v, w)) in a.iter().zip(b).enumerate() {
                walk(v, w, &format!("{path}[{i}]"), found);
            }
        }
        _ => {}
    }
}

/// An optional list written empty or as `null` (read as absent).
fn empty(value: &Value) -> bool {
    value.is_null() || value.as_array().is_some_and(Vec::is_empty)
}

/// The top-level keys of [`Truth`], those it leaves out when empty included:
/// the keys of a truth with one of everything, written.
fn top_level_keys() -> Vec<String> {
    let full = Truth {
        effect_details: vec![super::EffectTruth {
            name: String::new(),
            bearing: String::new(),
            parameters: Default::default(),
        }],
        bases: vec![super::BaseTruth {
            name: String::new(),
            bearings: Vec::new(),
            m_y: 0.0,
            m_z: 0.0,
            k_y: 0.0,
            k_z: 0.0,
            c_y: 0.0,
            c_z: 0.0,
            eta: 0.0,
        }],
        ..Truth::default()
    };
    serde_json::to_value(full)
        .ok()
        .and_then(|v| v.as_object().map(|o| o.keys().cloned().collect()))
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn notes(text: &str) -> Vec<String> {
        let truth: Truth = serde_json::from_str(text).unwrap();
        unread(text, &truth)
    }

    #[test]
    fn a_truth_with_only_known_keys_and_names_has_no_note() {
        let text = r#"{"pedestals": [{"bearing": "left", "k_y": 1e7, "k_z": 1e7, "m": 80,
            "c_y": 0, "c_z": 0}], "effects": ["probe_runout"], "effect_details": [],
            "bases": [], "source": "ROSS"}"#;
        assert!(notes(text).is_empty(), "{:?}", notes(text));
        let text = r#"{"pedestals": [], "effect_details": [], "bases": []}"#;
        assert!(notes(text).is_empty(), "{:?}", notes(text));
    }

    #[test]
    fn a_misspelt_key_is_named_at_its_place_with_the_keys_expected() {
        let text = "{\"pedestals\": [{\"bearing\": \"left\", \"k_y\": 1e7, \"k_z\": 1e7, \"m\": 80,\n  \"c_y\": 0, \"c_z\": 0, \"k_yy\": 2e7}]}";
        let n = notes(text);
        assert_eq!(n.len(), 1, "{n:?}");
        assert!(
            n[0].starts_with("2:23: key `k_yy` (pedestals[0].k_yy)"),
            "{n:?}"
        );
        assert!(n[0].contains("bearing, c_y, c_z, k_y, k_z, m"), "{n:?}");
        let text = "{\"pedestals\": [], \"efects\": []}";
        let n = notes(text);
        assert_eq!(n.len(), 1, "{n:?}");
        assert!(n[0].starts_with("1:19: key `efects` (efects)"), "{n:?}");
        assert!(n[0].contains("source"), "{n:?}");
    }

    #[test]
    fn an_unknown_effect_name_is_named_at_its_place() {
        let text = "{\"pedestals\": [],\n \"effects\": [\"probe_runout\", \"probe_runnout\"]}";
        let n = notes(text);
        assert_eq!(n.len(), 1, "{n:?}");
        assert!(
            n[0].starts_with("2:30: effects[1] `probe_runnout` is not an effect"),
            "{n:?}"
        );
    }
}
