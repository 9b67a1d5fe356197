//! Report primitives: plot models rendered to SVG ([`plot`]), one table model rendered to
//! Markdown, CSV and HTML ([`table`]), a self-contained HTML page builder ([`html`]) and an
//! all-or-nothing writer for a folder of outputs ([`output`]). Nothing here knows about the
//! model; callers build the values.

pub mod dive_plot;
pub mod html;
pub mod journal;
pub mod output;
pub mod overlay;
pub mod plot;
pub mod table;
