//! Plan reports: the paper's tables and figures, as text and SVG.
