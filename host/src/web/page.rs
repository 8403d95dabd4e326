//! The page: one HTML document with its style and script compiled in
//! (`assets/`, no library, no network), the joint colours of the CLI's
//! plots (`triquint_plot::JOINT_COLOURS`), and the current state and trace
//! history embedded so it shows the machine before the stream's first event.

use serde_json::json;

use super::event::{EVENT_HZ, event};
use super::guard::Policy;
use super::model::Model;

const HTML: &str = include_str!("assets/index.html");
const STYLE: &str = include_str!("assets/style.css");
const SCRIPT: &str = include_str!("assets/app.js");

/// JSON that is safe inside a `<script>` element.
fn script_safe(s: &str) -> String {
    s.replace('<', "\\u003c")
        .replace('>', "\\u003e")
        .replace('&', "\\u0026")
}

/// The page for `model`'s current state.
pub fn render(model: &Model, policy: &Policy) -> String {
    let colours: Vec<String> = triquint_plot::JOINT_COLOURS
        .iter()
        .map(|c| format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2))
        .collect();
    let config = json!({
        "colours": colours,
        "event_hz": EVENT_HZ,
        "control": policy.allow_control,
        "replay": model.replay,
    });
    let initial = event(model, None, None);
    HTML.replace("/*STYLE*/", STYLE)
        .replace("/*SCRIPT*/", SCRIPT)
        .replace("{{SOURCE}}", &html_escape(&model.source))
        .replace("/*CONFIG*/null", &script_safe(&config.to_string()))
        .replace("/*INITIAL*/null", &script_safe(&initial.to_string()))
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
