//! A self-contained HTML page: title, headings, Markdown-ish paragraphs, inline SVG figures
//! and tables. No JavaScript, no external files; the output is well-formed XHTML (it parses
//! as XML), so a test can check it with any XML parser. The same page also renders to
//! Markdown ([`Page::to_markdown`]), with figures as links to their SVG files.
//!
//! Paragraph text understands a small Markdown subset: blank lines separate paragraphs; lines
//! starting with `- ` form a bullet list; `**bold**`, `*italic*`, `` `code` `` and
//! `[text](url)` inline. Everything else is escaped.

use std::fmt::Write as _;

use super::table::{html_escape, Table};

/// One block of a page.
#[derive(Debug, Clone, PartialEq)]
enum Block {
    Heading(u8, String),
    Text(String),
    Figure {
        svg: String,
        file: Option<String>,
        caption: String,
    },
    Table(Table),
    Pre(String),
}

/// A page under construction.
#[derive(Debug, Clone, PartialEq)]
pub struct Page {
    /// Page title (`<title>` and the top `<h1>`).
    pub title: String,
    blocks: Vec<Block>,
}

/// A small print-friendly stylesheet, inlined in every page.
const STYLE: &str = "body{font-family:sans-serif;max-width:64rem;margin:2rem auto;padding:0 1rem;line-height:1.45;color:#111}
h1,h2,h3{line-height:1.2}
table{border-collapse:collapse;margin:1rem 0}
caption{font-weight:bold;text-align:left;padding:.3rem 0}
th,td{border:1px solid #bbb;padding:.25rem .6rem}
th{background:#f0f0f0}
td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
figure{margin:1.5rem 0}
figure svg{max-width:100%;height:auto}
figcaption{font-size:.9rem;color:#333}
pre,code{background:#f6f6f6}
pre{padding:.5rem;overflow-x:auto}
@media print{body{max-width:none}figure{break-inside:avoid}}";

impl Page {
    /// An empty page.
    pub fn new(title: impl Into<String>) -> Self {
        Page {
            title: title.into(),
            blocks: Vec::new(),
        }
    }

    /// A section heading (`<h2>`).
    pub fn section(&mut self, title: impl Into<String>) -> &mut Self {
        self.heading(2, title)
    }

    /// A heading of level 2..=6 (level 1 is the page title; other levels are clamped).
    pub fn heading(&mut self, level: u8, text: impl Into<String>) -> &mut Self {
        self.blocks
            .push(Block::Heading(level.clamp(2, 6), text.into()));
        self
    }

    /// Markdown-ish text: paragraphs, bullet lists, inline emphasis, code and links.
    pub fn text(&mut self, md: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Text(md.into()));
        self
    }

    /// Preformatted text (a command, a log excerpt).
    pub fn pre(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Pre(text.into()));
        self
    }

    /// An inline SVG figure with a caption; `file` is the SVG's file name beside the page,
    /// used as the image link in the Markdown rendering. Errors if `svg` is not an `<svg>`
    /// document (an XML declaration before it is dropped).
    pub fn figure(
        &mut self,
        svg: &str,
        file: Option<&str>,
        caption: impl Into<String>,
    ) -> Result<&mut Self, String> {
        let mut body = svg.trim_start();
        if body.starts_with("<?xml") {
            body = body
                .find("?>")
                .map(|i| body[i + 2..].trim_start())
                .unwrap_or(body);
        }
        if !body.starts_with("<svg") || !body.trim_end().ends_with("</svg>") {
            return Err("a figure must be an SVG document (<svg …>…</svg>)".into());
        }
        self.blocks.push(Block::Figure {
            svg: body.trim_end().to_string(),
            file: file.map(str::to_string),
            caption: caption.into(),
        });
        Ok(self)
    }

    /// A table.
    pub fn table(&mut self, t: &Table) -> &mut Self {
        let mut t = t.clone();
        // a table right under a heading of the same words does not repeat them
        if let Some(Block::Heading(_, h)) = self.blocks.last() {
            if h.trim() == t.title.trim() {
                t.title.clear();
            }
        }
        self.blocks.push(Block::Table(t));
        self
    }

    /// The whole page as an XHTML-compatible HTML5 document.
    pub fn to_html(&self) -> Result<String, String> {
        let mut s = String::new();
        s.push_str("<!DOCTYPE html>\n<html xmlns=\"http://www.w3.org/1999/xhtml\" lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n");
        s.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"/>\n");
        let _ = writeln!(s, "<title>{}</title>", html_escape(&self.title));
        let _ = writeln!(s, "<style>\n{STYLE}\n</style>\n</head>\n<body>");
        let _ = writeln!(s, "<h1>{}</h1>", html_escape(&self.title));
        for b in &self.blocks {
            match b {
                Block::Heading(l, t) => {
                    let _ = writeln!(s, "<h{l}>{}</h{l}>", html_escape(t));
                }
                Block::Text(md) => s.push_str(&md_blocks_to_html(md)),
                Block::Pre(t) => {
                    let _ = writeln!(s, "<pre>{}</pre>", html_escape(t));
                }
                Block::Figure { svg, caption, .. } => {
                    let _ = writeln!(
                        s,
                        "<figure>\n{svg}\n<figcaption>{}</figcaption>\n</figure>",
                        inline_html(caption)
                    );
                }
                Block::Table(t) => s.push_str(&t.to_html()?),
            }
        }
        s.push_str("</body>\n</html>\n");
        Ok(s)
    }

    /// The same page as Markdown; figures become `![caption](file)` (or just their caption
    /// in italics when they have no file).
    pub fn to_markdown(&self) -> Result<String, String> {
        let mut s = format!("# {}\n", self.title);
        for b in &self.blocks {
            s.push('\n');
            match b {
                Block::Heading(l, t) => {
                    let _ = writeln!(s, "{} {t}", "#".repeat(*l as usize));
                }
                Block::Text(md) => {
                    let _ = writeln!(s, "{}", md.trim_end());
                }
                Block::Pre(t) => {
                    let _ = writeln!(s, "```\n{}\n```", t.trim_end());
                }
                Block::Figure { file, caption, .. } => match file {
                    Some(f) => {
                        let _ =
                            writeln!(s, "![{}]({f})\n\n*{caption}*", caption.replace(']', "\\]"));
                    }
                    None => {
                        let _ = writeln!(s, "*{caption}*");
                    }
                },
                Block::Table(t) => s.push_str(&t.to_markdown()?),
            }
        }
        Ok(s)
    }
}

/// Paragraphs and bullet lists of Markdown-ish text as HTML.
fn md_blocks_to_html(md: &str) -> String {
    let mut out = String::new();
    let mut para: Vec<&str> = Vec::new();
    let mut list: Vec<String> = Vec::new();
    let flush_para = |para: &mut Vec<&str>, out: &mut String| {
        if !para.is_empty() {
            let _ = writeln!(out, "<p>{}</p>", inline_html(&para.join(" ")));
            para.clear();
        }
    };
    let flush_list = |list: &mut Vec<String>, out: &mut String| {
        if !list.is_empty() {
            out.push_str("<ul>\n");
            for item in list.iter() {
                let _ = writeln!(out, "<li>{}</li>", inline_html(item));
            }
            out.push_str("</ul>\n");
            list.clear();
        }
    };
    for line in md.lines() {
        let t = line.trim();
        if t.is_empty() {
            flush_para(&mut para, &mut out);
            flush_list(&mut list, &mut out);
        } else if let Some(item) = t.strip_prefix("- ").or_else(|| t.strip_prefix("* ")) {
            flush_para(&mut para, &mut out);
            list.push(item.to_string());
        } else if !list.is_empty() && line.starts_with(char::is_whitespace) {
            // Continuation of the last list item.
            let last = list.last_mut().expect("non-empty");
            last.push(' ');
            last.push_str(t);
        } else {
            flush_list(&mut list, &mut out);
            para.push(t);
        }
    }
    flush_para(&mut para, &mut out);
    flush_list(&mut list, &mut out);
    out
}

/// Inline Markdown (`**bold**`, `*italic*`, `` `code` ``, `[text](url)`) to escaped HTML.
/// Unmatched markers are kept as literal characters.
fn inline_html(s: &str) -> String {
    let chars: Vec<char> = s.chars().collect();
    let mut out = String::new();
    let mut i = 0;
    let find = |from: usize, pat: &[char]| -> Option<usize> {
        (from..chars.len().saturating_sub(pat.len() - 1)).find(|&j| chars[j..].starts_with(pat))
    };
    let text = |a: usize, b: usize| chars[a..b].iter().collect::<String>();
    while i < chars.len() {
        let c = chars[i];
        if c == '`' {
            if let Some(j) = find(i + 1, &['`']) {
                let _ = write!(out, "<code>{}</code>", html_escape(&text(i + 1, j)));
                i = j + 1;
                continue;
            }
        } else if c == '*' && chars.get(i + 1) == Some(&'*') {
            if let Some(j) = find(i + 2, &['*', '*']).filter(|&j| j > i + 2) {
                let _ = write!(out, "<strong>{}</strong>", inline_html(&text(i + 2, j)));
                i = j + 2;
                continue;
            }
        } else if c == '*' {
            if let Some(j) = find(i + 1, &['*']).filter(|&j| j > i + 1) {
                let _ = write!(out, "<em>{}</em>", inline_html(&text(i + 1, j)));
                i = j + 1;
                continue;
            }
        } else if c == '[' {
            if let Some(j) = find(i + 1, &[']', '(']) {
                if let Some(k) = find(j + 2, &[')']) {
                    let _ = write!(
                        out,
                        "<a href=\"{}\">{}</a>",
                        html_escape(&text(j + 2, k)),
                        inline_html(&text(i + 1, j))
                    );
                    i = k + 1;
                    continue;
                }
            }
        }
        out.push_str(&html_escape(&c.to_string()));
        i += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_under_a_heading_of_the_same_words_does_not_repeat_them() {
        use crate::report::table::{Column, Table};
        let mut p = Page::new("t");
        p.section("Schedules");
        p.table(&Table::new("Schedules", vec![Column::plain("a")]));
        p.table(&Table::new("Other", vec![Column::plain("b")]));
        let md = p.to_markdown().unwrap();
        assert_eq!(md.matches("Schedules").count(), 1, "{md}");
        assert!(md.contains("### Other"), "{md}");
    }

    #[test]
    fn inline_markup() {
        assert_eq!(
            inline_html("a **b** *c* `x<y` [d](e.svg) 2 * 3 < 4"),
            "a <strong>b</strong> <em>c</em> <code>x&lt;y</code> <a href=\"e.svg\">d</a> 2 * 3 &lt; 4"
        );
    }

    #[test]
    fn paragraphs_and_lists() {
        let h = md_blocks_to_html("one\ntwo\n\n- a\n- b\n  c\n\nthree");
        assert_eq!(
            h,
            "<p>one two</p>\n<ul>\n<li>a</li>\n<li>b c</li>\n</ul>\n<p>three</p>\n"
        );
    }
}
