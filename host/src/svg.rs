//! Minimal SVG line charts for plans and simulation results.
