//! One server-sent event of the page: the state and the traces new since
//! the client's cursor. The page embeds the first one, the server streams
//! the rest, so both use this module.

use serde_json::{Value as Json, json};

use super::model::Model;

/// Events per second on `/api/events`.
pub const EVENT_HZ: u64 = 20;
/// Samples per series in one event (the first one carries the history).
const MAX_EVENT_SAMPLES: usize = 20_000;

/// One event: the state and what is new since `cursor` (bus time, µs).
pub fn event(model: &Model, cursor: Option<u64>, planned_seen: Option<u64>) -> Json {
    let mut state = model.state_json();
    let delta = model.traces.delta(cursor, MAX_EVENT_SAMPLES);
    if let Some(o) = state.as_object_mut() {
        o.insert("traces".into(), json!(delta.series));
        o.insert("trail".into(), json!(model.trail_since(cursor)));
        if planned_seen != Some(model.planned_version) {
            o.insert("planned".into(), json!(model.planned));
        }
    }
    state
}
