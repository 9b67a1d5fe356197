//! One table model rendered to Markdown, CSV and HTML. A number is formatted once
//! ([`Cell::to_text`]) and that same string goes into all three outputs, so a reader of the CSV
//! and a reader of the report see identical digits; the one exception is the power of ten of a
//! [`NumberFormat::Sig`] number outside 10⁻³…10⁶, written `1.95×10⁻¹²` for reading and
//! `1.95e-12` in the CSV ([`Cell::to_csv_text`]), the same digits.

use std::fmt::Write as _;

/// A column: a name and, where it has one, a unit.
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    /// Name, e.g. `radius`. In CSV headers it is joined to the unit with `_` (`radius_m`), so
    /// for CSV it should be a plain identifier.
    pub name: String,
    /// Unit, e.g. `m`, `Pa`, `m3`; `None` for counts, labels and ratios.
    pub unit: Option<String>,
}

impl Column {
    /// A column with a unit.
    pub fn new(name: impl Into<String>, unit: impl Into<String>) -> Self {
        Column {
            name: name.into(),
            unit: Some(unit.into()),
        }
    }
    /// A column without a unit.
    pub fn plain(name: impl Into<String>) -> Self {
        Column {
            name: name.into(),
            unit: None,
        }
    }
    /// CSV header: `name_unit` (or `name`).
    pub fn csv_header(&self) -> String {
        match &self.unit {
            Some(u) => format!("{}_{}", self.name, u),
            None => self.name.clone(),
        }
    }
    /// Human header for Markdown and HTML: `name (unit)` (or `name`).
    pub fn display_header(&self) -> String {
        match &self.unit {
            Some(u) => format!("{} ({})", self.name, u),
            None => self.name.clone(),
        }
    }
}

/// How a number is printed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NumberFormat {
    /// Fixed decimals, e.g. `Fixed(3)` → `1.235`.
    Fixed(usize),
    /// Significant digits in scientific notation, e.g. `Sci(3)` → `1.23e-4`.
    Sci(usize),
    /// Significant digits in plain decimal notation, for a number in its natural unit:
    /// `Sig(4)` → `90.38`, `0.07397`, `150.2`, `0.01348`. Outside 10⁻³ ≤ |v| < 10⁶ (a
    /// number that the unit does not suit, e.g. a numerical zero) with a power of ten,
    /// `1.945×10⁻¹²`.
    Sig(usize),
}

/// One table cell.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// Text, printed as is (escaped for Markdown and HTML).
    Text(String),
    /// A number with its display format. Non-finite numbers print as `NaN`, `inf`, `-inf`.
    Number(f64, NumberFormat),
    /// No value (empty in CSV and in the report).
    Empty,
}

impl Cell {
    /// A text cell.
    pub fn text(s: impl Into<String>) -> Self {
        Cell::Text(s.into())
    }
    /// A number with fixed decimals.
    pub fn fixed(v: f64, decimals: usize) -> Self {
        Cell::Number(v, NumberFormat::Fixed(decimals))
    }
    /// A number in scientific notation with `digits` significant digits (≥ 1).
    pub fn sci(v: f64, digits: usize) -> Self {
        Cell::Number(v, NumberFormat::Sci(digits))
    }

    /// A number with `digits` significant digits (≥ 1) in plain decimal notation
    /// ([`NumberFormat::Sig`]).
    pub fn sig(v: f64, digits: usize) -> Self {
        Cell::Number(v, NumberFormat::Sig(digits))
    }

    /// The printed value for Markdown and HTML (and the CSV, but for the power of ten of a
    /// [`NumberFormat::Sig`] number, [`Cell::to_csv_text`]).
    pub fn to_text(&self) -> String {
        match self {
            Cell::Number(v, NumberFormat::Sig(n)) if v.is_finite() => sig_text(*v, *n, true),
            Cell::Text(s) => s.clone(),
            Cell::Empty => String::new(),
            Cell::Number(v, _) if v.is_nan() => "NaN".into(),
            Cell::Number(v, _) if v.is_infinite() => {
                if *v > 0.0 {
                    "inf".into()
                } else {
                    "-inf".into()
                }
            }
            Cell::Number(v, NumberFormat::Fixed(d)) => {
                let s = format!("{v:.d$}");
                // No negative zero: "-0.000" prints as "0.000".
                if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
                    s[1..].to_string()
                } else {
                    s
                }
            }
            Cell::Number(v, NumberFormat::Sci(n)) => {
                let d = n.saturating_sub(1);
                format!("{v:.d$e}")
            }
            Cell::Number(v, NumberFormat::Sig(n)) => sig_text(*v, *n, true),
        }
    }

    /// The printed value for the CSV: [`Cell::to_text`] with a power of ten written `e-12`,
    /// so that every CSV reader parses it.
    pub fn to_csv_text(&self) -> String {
        match self {
            Cell::Number(v, NumberFormat::Sig(n)) if v.is_finite() => sig_text(*v, *n, false),
            _ => self.to_text(),
        }
    }
}

/// `v` (finite) with `n` significant digits: plain decimals for 10⁻³ ≤ |v| < 10⁶, else a
/// mantissa and a power of ten (`×10⁻¹²` when `pretty`, `e-12` otherwise). The exponent is
/// taken after rounding, so 99.996 with four digits prints `100.0`, not `100.00`.
pub fn sig_text(v: f64, n: usize, pretty: bool) -> String {
    let n = n.max(1);
    if v == 0.0 {
        return "0".into();
    }
    let sci = format!("{v:.*e}", n - 1);
    let (mant, exp) = sci.split_once('e').unwrap_or((&sci, "0"));
    let e: i32 = exp.parse().unwrap_or(0);
    if (-3..6).contains(&e) {
        let d = (n as i32 - 1 - e).max(0) as usize;
        return format!("{v:.d$}");
    }
    if !pretty {
        return format!("{mant}e{e}");
    }
    const SUP: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut p = String::new();
    if e < 0 {
        p.push('⁻');
    }
    for c in e.unsigned_abs().to_string().chars() {
        p.push(SUP[c.to_digit(10).unwrap_or(0) as usize]);
    }
    format!("{mant}×10{p}")
}

/// A table: title, columns, rows of cells (each row as long as `columns`).
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Title (Markdown heading text, HTML caption; not in the CSV).
    pub title: String,
    /// Columns.
    pub columns: Vec<Column>,
    /// Rows.
    pub rows: Vec<Vec<Cell>>,
}

impl Table {
    /// An empty table.
    pub fn new(title: impl Into<String>, columns: Vec<Column>) -> Self {
        Table {
            title: title.into(),
            columns,
            rows: Vec::new(),
        }
    }

    /// Append a row; errors if its length differs from the number of columns.
    pub fn push(&mut self, row: Vec<Cell>) -> Result<(), String> {
        if row.len() != self.columns.len() {
            return Err(format!(
                "table '{}': row of {} cells for {} columns",
                self.title,
                row.len(),
                self.columns.len()
            ));
        }
        self.rows.push(row);
        Ok(())
    }

    fn check(&self) -> Result<(), String> {
        for (i, r) in self.rows.iter().enumerate() {
            if r.len() != self.columns.len() {
                return Err(format!(
                    "table '{}': row {} has {} cells for {} columns",
                    self.title,
                    i + 1,
                    r.len(),
                    self.columns.len()
                ));
            }
        }
        Ok(())
    }

    /// GitHub-flavoured Markdown: a `###` heading with the title, then the table. Numbers
    /// are right-aligned. `|` and line breaks inside cells are escaped.
    pub fn to_markdown(&self) -> Result<String, String> {
        self.check()?;
        let mut s = String::new();
        if !self.title.is_empty() {
            let _ = writeln!(s, "### {}\n", md_escape(&self.title));
        }
        let head: Vec<String> = self
            .columns
            .iter()
            .map(|c| md_escape(&c.display_header()))
            .collect();
        let _ = writeln!(s, "| {} |", head.join(" | "));
        let align: Vec<&str> = (0..self.columns.len())
            .map(|j| if self.is_numeric(j) { "---:" } else { "---" })
            .collect();
        let _ = writeln!(s, "| {} |", align.join(" | "));
        for r in &self.rows {
            let cells: Vec<String> = r.iter().map(|c| md_escape(&c.to_text())).collect();
            let _ = writeln!(s, "| {} |", cells.join(" | "));
        }
        Ok(s)
    }

    /// CSV (RFC 4180 via the `csv` crate): header `name_unit`, then the rows.
    pub fn to_csv(&self) -> Result<String, String> {
        self.check()?;
        let mut w = csv::WriterBuilder::new()
            .terminator(csv::Terminator::Any(b'\n'))
            .from_writer(Vec::new());
        let e = |e: csv::Error| format!("table '{}': {e}", self.title);
        w.write_record(self.columns.iter().map(|c| c.csv_header()))
            .map_err(e)?;
        for r in &self.rows {
            w.write_record(r.iter().map(|c| c.to_csv_text()))
                .map_err(e)?;
        }
        let bytes = w
            .into_inner()
            .map_err(|e| format!("table '{}': {e}", self.title))?;
        String::from_utf8(bytes).map_err(|e| format!("table '{}': {e}", self.title))
    }

    /// An HTML (and XHTML-compatible) `<table>` with the title as `<caption>`; all text escaped.
    pub fn to_html(&self) -> Result<String, String> {
        self.check()?;
        let mut s = String::from("<table>\n");
        if !self.title.is_empty() {
            let _ = writeln!(s, "<caption>{}</caption>", html_escape(&self.title));
        }
        s.push_str("<thead><tr>");
        for c in &self.columns {
            let _ = write!(s, "<th>{}</th>", html_escape(&c.display_header()));
        }
        s.push_str("</tr></thead>\n<tbody>\n");
        for r in &self.rows {
            s.push_str("<tr>");
            for c in r {
                let class = if matches!(c, Cell::Number(..)) {
                    " class=\"num\""
                } else {
                    ""
                };
                let _ = write!(s, "<td{class}>{}</td>", html_escape(&c.to_text()));
            }
            s.push_str("</tr>\n");
        }
        s.push_str("</tbody>\n</table>\n");
        Ok(s)
    }

    fn is_numeric(&self, j: usize) -> bool {
        let mut any = false;
        for r in &self.rows {
            match &r[j] {
                Cell::Number(..) => any = true,
                Cell::Empty => {}
                // an approximate number ("≈ 0": zero within the round-off) aligns as a number
                Cell::Text(t) if t.starts_with('≈') => any = true,
                Cell::Text(_) => return false,
            }
        }
        any
    }
}

/// Escape text for a Markdown table cell: `\`, `|`, and the inline markup characters
/// `*`, `_`, `` ` ``, `<`, `[`; line breaks become spaces.
pub fn md_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '\\' | '|' | '*' | '_' | '`' | '<' | '[' | ']' => {
                out.push('\\');
                out.push(ch);
            }
            '\n' | '\r' => out.push(' '),
            _ => out.push(ch),
        }
    }
    out
}

/// Escape text for HTML/XML content and attribute values.
pub fn html_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            // Characters XML 1.0 forbids (C0 controls other than tab and line breaks).
            c if (c as u32) < 0x20 && !matches!(c, '\t' | '\n' | '\r') => {}
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn number_formats() {
        assert_eq!(Cell::fixed(1.23456, 3).to_text(), "1.235");
        assert_eq!(Cell::fixed(-0.0001, 2).to_text(), "0.00");
        assert_eq!(Cell::sci(0.000123456, 3).to_text(), "1.23e-4");
        assert_eq!(Cell::sci(f64::NAN, 3).to_text(), "NaN");
        assert_eq!(Cell::fixed(f64::NEG_INFINITY, 3).to_text(), "-inf");
        assert_eq!(Cell::Empty.to_text(), "");
    }

    #[test]
    fn significant_figures_in_the_natural_unit() {
        // the two examples: 9.038e1 µm and 7.397e-2 %
        assert_eq!(Cell::sig(90.38, 4).to_text(), "90.38");
        assert_eq!(Cell::sig(0.07397, 4).to_text(), "0.07397");
        assert_eq!(Cell::sig(150.24, 4).to_text(), "150.2");
        assert_eq!(Cell::sig(0.013476, 4).to_text(), "0.01348");
        assert_eq!(Cell::sig(-0.0051843, 4).to_text(), "-0.005184");
        assert_eq!(Cell::sig(123456.0, 4).to_text(), "123456");
        // rounding that carries into the next decade keeps n digits
        assert_eq!(Cell::sig(99.996, 4).to_text(), "100.0");
        assert_eq!(Cell::sig(0.0, 4).to_text(), "0");
        // a numerical zero keeps its power of ten, pretty for reading, e-notation in CSV
        let tiny = Cell::sig(1.9449e-12, 4);
        assert_eq!(tiny.to_text(), "1.945×10⁻¹²");
        assert_eq!(tiny.to_csv_text(), "1.945e-12");
        assert_eq!(Cell::sig(2.5e7, 2).to_text(), "2.5×10⁷");
        assert_eq!(Cell::sig(f64::NAN, 4).to_text(), "NaN");
    }

    #[test]
    fn escapes() {
        assert_eq!(md_escape("a|b_c"), "a\\|b\\_c");
        assert_eq!(html_escape("<a & 'b'>"), "&lt;a &amp; &#39;b&#39;&gt;");
    }
}
