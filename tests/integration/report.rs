//! Report primitives: SVG plots (well-formed, deterministic, labelled, robust to bad data),
//! tables (identical numbers in Markdown, CSV and HTML), the all-or-nothing output writer,
//! and the self-contained HTML page.

use std::path::Path;

use decophantom::report::html::Page;
use decophantom::report::output::{OutputSet, MARKER};
use decophantom::report::plot::{BarChart, LinePlot, PlotError, Series, DEFAULT_SIZE};
use decophantom::report::table::{Cell, Column, Table};

use crate::common::tempdir;

/// Parse as XML (roxmltree), panicking with the parser's message on malformed output.
fn parse_xml(text: &str) -> roxmltree::Document<'_> {
    let opt = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    roxmltree::Document::parse_with_options(text, opt).unwrap_or_else(|e| panic!("not XML: {e}"))
}

/// All `<text>` contents of an SVG.
fn texts(doc: &roxmltree::Document) -> Vec<String> {
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| n.text().unwrap_or("").trim().to_string())
        .collect()
}

fn radius_plot(n: usize) -> LinePlot {
    let mut p = LinePlot::new("Bubble radius <R> & growth", "time (s)", "radius (µm)");
    for k in 0..n {
        let pts = (0..200)
            .map(|i| {
                let t = i as f64;
                (t, 50.0 + 10.0 * k as f64 + 20.0 * (t / 30.0).sin())
            })
            .collect();
        p.series.push(Series::new(format!("bubble {k}"), pts));
    }
    p
}

#[test]
fn line_plot_is_wellformed_labelled_and_deterministic() {
    let p = radius_plot(3);
    let svg = p.to_svg().unwrap();
    assert_eq!(svg, p.to_svg().unwrap(), "same input, same bytes");
    let doc = parse_xml(&svg);
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "svg");
    assert_eq!(
        root.attribute("width"),
        Some(DEFAULT_SIZE.0.to_string().as_str())
    );
    let t = texts(&doc);
    for want in [
        "Bubble radius <R> & growth",
        "time (s)",
        "radius (µm)",
        "bubble 0",
        "bubble 2",
    ] {
        assert!(
            t.iter().any(|x| x == want),
            "missing label {want:?} in {t:?}"
        );
    }
    // Tick labels are there too (numbers on both axes).
    assert!(
        t.iter().filter(|x| x.parse::<f64>().is_ok()).count() >= 6,
        "{t:?}"
    );
    // Text carries a font family and a size the viewer can use without font files.
    let title = doc
        .descendants()
        .find(|n| n.has_tag_name("text") && n.text().map(str::trim) == Some("time (s)"))
        .unwrap();
    assert_eq!(title.attribute("font-family"), Some("sans-serif"));
    let size: f64 = title.attribute("font-size").unwrap().parse().unwrap();
    assert!(
        size >= 14.0,
        "axis label font {size}px is too small to print"
    );
}

#[test]
fn many_series_get_distinct_colours_and_markers() {
    let p = radius_plot(9);
    let svg = p.to_svg().unwrap();
    let doc = parse_xml(&svg);
    // Stroke colours of the drawn lines (polylines of width 2).
    let mut colours: Vec<&str> = doc
        .descendants()
        .filter(|n| n.has_tag_name("polyline") && n.attribute("stroke-width") == Some("2"))
        .filter_map(|n| n.attribute("stroke"))
        .collect();
    colours.sort();
    colours.dedup();
    assert!(colours.len() >= 7, "{colours:?}");
    // Markers: circles, polygons or rects in the series colours; more than 6 series -> markers.
    let circles = doc
        .descendants()
        .filter(|n| n.has_tag_name("circle"))
        .count();
    assert!(circles >= 10, "expected markers, found {circles} circles");
    // Series 8 and 9 are dashed: many short polylines.
    let few = radius_plot(3).to_svg().unwrap();
    let count = |s: &str| s.matches("<polyline").count();
    assert!(count(&svg) > count(&few) + 50);
}

#[test]
fn bad_data_is_skipped_or_refused_never_a_panic() {
    // NaN and infinities break the line; the rest is drawn.
    let p = LinePlot::new("gaps", "t (s)", "V (m3)").with(Series::new(
        "v",
        vec![
            (0.0, 1.0),
            (1.0, f64::NAN),
            (2.0, 2.0),
            (f64::INFINITY, 3.0),
            (4.0, 1.5),
        ],
    ));
    parse_xml(&p.to_svg().unwrap());
    // Nothing drawable at all.
    let p = LinePlot::new("empty", "t (s)", "V (m3)").with(Series::new("v", vec![(0.0, f64::NAN)]));
    assert_eq!(p.to_svg(), Err(PlotError::NoData("empty".into())));
    assert!(LinePlot::new("none", "x", "y").to_svg().is_err());
    // Log axis: zero and negative values are skipped.
    let mut p = LinePlot::new("log", "t (s)", "V (m3)").with(Series::new(
        "v",
        vec![(0.0, 0.0), (1.0, 1e-12), (2.0, 3e-10), (3.0, -1.0)],
    ));
    p.log_y = true;
    parse_xml(&p.to_svg().unwrap());
    // A single point, a constant series: degenerate ranges are widened.
    let p = LinePlot::new("one", "t (s)", "p (Pa)").with(Series::new("p", vec![(5.0, 1e5)]));
    parse_xml(&p.to_svg().unwrap());
}

#[test]
fn secondary_axis_series_is_labelled() {
    let mut p = LinePlot::new("Pressure and radius", "time (s)", "radius (µm)")
        .with(Series::new("radius", vec![(0.0, 40.0), (60.0, 90.0)]))
        .with(Series::new("ambient", vec![(0.0, 1e5), (60.0, 2.4e5)]).on_secondary());
    assert!(
        p.to_svg().is_err(),
        "a secondary series needs a secondary label"
    );
    p.secondary_y_label = Some("pressure (Pa)".into());
    let svg = p.to_svg().unwrap();
    let doc = parse_xml(&svg);
    let t = texts(&doc);
    assert!(t.iter().any(|x| x == "pressure (Pa)"), "{t:?}");
    // The primary axis label is drawn once (left only), not on the right axis as well.
    assert_eq!(t.iter().filter(|x| *x == "radius (µm)").count(), 1, "{t:?}");
    assert!(t.iter().any(|x| x == "ambient (right axis)"), "{t:?}");
}

#[test]
fn bar_chart_groups_and_errors() {
    let c = BarChart {
        title: "Criteria per schedule".into(),
        x_label: "criterion".into(),
        y_label: "value / limit".into(),
        categories: vec![
            "peak total bubble volume".into(),
            "peak radius".into(),
            "P(DCS)".into(),
        ],
        groups: vec!["GF 30/85".into(), "VPM-B +2".into()],
        values: vec![vec![0.5, 0.7], vec![1.2, f64::NAN], vec![-0.1, 0.3]],
        reference: Some((1.0, "limit".into())),
        size: DEFAULT_SIZE,
    };
    let svg = c.to_svg().unwrap();
    assert_eq!(svg, c.to_svg().unwrap());
    let doc = parse_xml(&svg);
    let t = texts(&doc);
    for want in [
        "Criteria per schedule",
        "value / limit",
        "GF 30/85",
        "VPM-B +2",
        "limit",
        "P(DCS)",
        "peak radius",
    ] {
        assert!(t.iter().any(|x| x == want), "missing {want:?} in {t:?}");
    }
    // Five finite values -> five bars in the two group colours (plus legend swatches).
    let fill = |c: &str| {
        doc.descendants()
            .filter(|n| n.has_tag_name("rect") && n.attribute("fill") == Some(c))
            .count()
    };
    assert_eq!(fill("#0072B2") + fill("#D55E00"), 5 + 2);

    let mut bad = c.clone();
    bad.values.pop();
    assert!(matches!(bad.to_svg(), Err(PlotError::Invalid { .. })));
    let mut nan = c.clone();
    nan.values = vec![vec![f64::NAN; 2]; 3];
    assert!(matches!(nan.to_svg(), Err(PlotError::NoData(_))));
}

fn sample_table() -> Table {
    let mut t = Table::new(
        "Bubbles | final",
        vec![
            Column::plain("bubble"),
            Column::new("radius", "m"),
            Column::new("volume", "m3"),
            Column::plain("note"),
        ],
    );
    let rows = [
        (0, 1.234_567e-4, 7.1e-12, "grew"),
        (1, 2.0e-5, f64::NAN, "a, \"b\" <c> & d"),
    ];
    for (i, r, v, n) in rows {
        t.push(vec![
            Cell::fixed(i as f64, 0),
            Cell::sci(r, 4),
            Cell::sci(v, 3),
            Cell::text(n),
        ])
        .unwrap();
    }
    t.push(vec![
        Cell::text("total"),
        Cell::Empty,
        Cell::fixed(-0.0, 2),
        Cell::Empty,
    ])
    .unwrap();
    t
}

#[test]
fn table_numbers_print_identically_in_markdown_csv_and_html() {
    let t = sample_table();
    let csv_text = t.to_csv().unwrap();
    let md = t.to_markdown().unwrap();
    let html = t.to_html().unwrap();

    let mut r = csv::Reader::from_reader(csv_text.as_bytes());
    let header: Vec<String> = r.headers().unwrap().iter().map(str::to_string).collect();
    assert_eq!(header, ["bubble", "radius_m", "volume_m3", "note"]);
    let csv_rows: Vec<Vec<String>> = r
        .records()
        .map(|rec| rec.unwrap().iter().map(str::to_string).collect())
        .collect();
    // Independent expectation: Rust's own formatting of the values.
    assert_eq!(csv_rows[0][1], format!("{:.3e}", 1.234_567e-4));
    assert_eq!(csv_rows[0][1], "1.235e-4");
    assert_eq!(csv_rows[1][2], "NaN");
    assert_eq!(csv_rows[1][3], "a, \"b\" <c> & d");
    assert_eq!(csv_rows[2][2], "0.00");

    // Markdown: table lines after the heading, cells split on unescaped '|'.
    let md_rows: Vec<Vec<String>> = md
        .lines()
        .filter(|l| l.starts_with('|'))
        .skip(2)
        .map(|l| {
            let inner = &l[1..l.len() - 1];
            inner.split(" | ").map(|c| c.trim().to_string()).collect()
        })
        .collect();
    let html_doc = parse_xml(&html);
    let html_rows: Vec<Vec<String>> = html_doc
        .descendants()
        .filter(|n| n.has_tag_name("tr"))
        .skip(1)
        .map(|tr| {
            tr.children()
                .filter(|c| c.has_tag_name("td"))
                .map(|td| td.text().unwrap_or("").to_string())
                .collect()
        })
        .collect();
    assert_eq!(md_rows.len(), 3);
    assert_eq!(html_rows.len(), 3);
    for i in 0..3 {
        for j in 0..3 {
            // Numeric columns: byte-identical in all three.
            assert_eq!(md_rows[i][j], csv_rows[i][j], "row {i} col {j}");
            assert_eq!(html_rows[i][j], csv_rows[i][j], "row {i} col {j}");
        }
        assert_eq!(html_rows[i][3], csv_rows[i][3]);
    }
    assert!(md.contains("radius (m)") && md.contains("Bubbles \\| final"));
    assert!(t.clone().push(vec![Cell::Empty]).is_err());
}

#[test]
fn output_set_is_written_whole_or_not_at_all() {
    let base = tempdir("report-output");
    let out = base.join("run");
    let mut a = OutputSet::new();
    a.add("scores.csv", "a,b\n1,2\n");
    a.add("plots/radius.svg", "<svg/>");
    a.commit(&out).unwrap();
    assert_eq!(
        std::fs::read_to_string(out.join("scores.csv")).unwrap(),
        "a,b\n1,2\n"
    );
    assert!(out.join("plots/radius.svg").is_file() && out.join(MARKER).is_file());

    // A second run replaces the folder: files not in the new set are gone.
    let mut b = OutputSet::new();
    b.add("scores.csv", "a,b\n3,4\n");
    b.commit(&out).unwrap();
    assert_eq!(
        std::fs::read_to_string(out.join("scores.csv")).unwrap(),
        "a,b\n3,4\n"
    );
    assert!(!out.join("plots").exists());

    // Failure while writing (a file name longer than any file system allows, after a good
    // file): the previous output stays exactly as it was and no staging folder remains.
    let mut c = OutputSet::new();
    c.add("scores.csv", "a,b\n5,6\n");
    c.add("x".repeat(300), "too long a name");
    assert!(c.commit(&out).is_err());
    assert_eq!(
        std::fs::read_to_string(out.join("scores.csv")).unwrap(),
        "a,b\n3,4\n"
    );
    let leftovers: Vec<String> = std::fs::read_dir(&base)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(leftovers, ["run"], "staging or old folders left behind");

    // A failing first commit creates nothing.
    assert!(c.commit(base.join("fresh")).is_err());
    assert!(!base.join("fresh").exists());

    // A folder that decophantom did not write is refused and left alone.
    let foreign = base.join("mine");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("thesis.tex"), "precious").unwrap();
    let e = a.commit(&foreign).unwrap_err();
    assert!(e.to_string().contains("not written by decophantom"), "{e}");
    assert_eq!(
        std::fs::read_to_string(foreign.join("thesis.tex")).unwrap(),
        "precious"
    );
    assert!(!foreign.join("scores.csv").exists());

    // An empty existing folder is fine; bad relative paths are refused before writing.
    let empty = base.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    a.commit(&empty).unwrap();
    let mut d = OutputSet::new();
    d.add("../escape.csv", "x");
    assert!(d.commit(base.join("d")).is_err());
    assert!(!base.join("escape.csv").exists() && !base.join("d").exists());
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn html_page_is_selfcontained_wellformed_xml() {
    let svg = radius_plot(2).to_svg().unwrap();
    let mut page = Page::new("Decompression report: 45 m / 25 min & <test>");
    page.section("Schedule")
        .text("Planned with **ZH-L16C** GF 30/85; see `scores.csv` and [the plot](radius.svg).\n\n- stops: 2\n- runtime < 60 min");
    page.figure(&svg, Some("radius.svg"), "Bubble radius vs time")
        .unwrap();
    page.table(&sample_table());
    page.pre("decophantom evaluate --depth 45 --time 25");
    let html = page.to_html().unwrap();
    assert_eq!(html, page.to_html().unwrap());
    let doc = parse_xml(&html);
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "html");
    assert!(
        doc.descendants().all(|n| !n.has_tag_name("script")),
        "no JavaScript"
    );
    // Nothing loaded from outside: no src attributes, no stylesheet links.
    assert!(doc
        .descendants()
        .all(|n| n.attribute("src").is_none() && !n.has_tag_name("link")));
    let svg_node = doc
        .descendants()
        .find(|n| n.tag_name().name() == "svg")
        .expect("inline SVG");
    assert_eq!(
        svg_node.tag_name().namespace(),
        Some("http://www.w3.org/2000/svg")
    );
    assert!(doc
        .descendants()
        .any(|n| n.has_tag_name(("http://www.w3.org/1999/xhtml", "table"))));
    let h1 = doc
        .descendants()
        .find(|n| n.tag_name().name() == "h1")
        .unwrap();
    assert_eq!(
        h1.text(),
        Some("Decompression report: 45 m / 25 min & <test>")
    );
    assert!(doc.descendants().any(|n| n.tag_name().name() == "strong"));
    assert_eq!(
        doc.descendants()
            .filter(|n| n.tag_name().name() == "li")
            .count(),
        2
    );

    let md = page.to_markdown().unwrap();
    assert!(md.starts_with("# Decompression report"));
    assert!(md.contains("![Bubble radius vs time](radius.svg)"));
    assert!(md.contains("| bubble | radius (m) |"));
    assert!(page.figure("<p>no</p>", None, "x").is_err());
    let _ = Path::new("");
}

/// `<text>` elements as (content, x, y) in px.
fn placed_texts(doc: &roxmltree::Document) -> Vec<(String, f64, f64)> {
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| {
            let num = |a: &str| {
                n.attribute(a)
                    .and_then(|v| v.parse().ok())
                    .unwrap_or(f64::NAN)
            };
            (
                n.text().unwrap_or("").trim().to_string(),
                num("x"),
                num("y"),
            )
        })
        .collect()
}

#[test]
fn depth_axis_increases_downward_and_log_x_is_a_log_axis() {
    // a dive: 0 → 45 m → 0; with y_down the 40 m tick is drawn below the 0 m tick (SVG y grows
    // downward) and no tick reads negative
    let mut p = LinePlot::new("Dive", "time (min)", "depth (m)");
    p.y_down = true;
    p = p.with(Series::new(
        "dive",
        vec![
            (0.0, 0.0),
            (2.0, 45.0),
            (25.0, 45.0),
            (40.0, 0.0),
            (60.0, 0.0),
        ],
    ));
    let svg = p.to_svg().unwrap();
    let doc = parse_xml(&svg);
    let t = placed_texts(&doc);
    let y_of = |label: &str| {
        t.iter()
            .filter(|(s, x, _)| s == label && *x < 130.0)
            .map(|(_, _, y)| *y)
            .next()
            .unwrap_or_else(|| panic!("no y tick {label}: {t:?}"))
    };
    assert!(
        y_of("40") > y_of("0") + 300.0,
        "{} {}",
        y_of("40"),
        y_of("0")
    );
    assert!(!t.iter().any(|(s, _, _)| s.starts_with('-')), "{t:?}");
    // yo-yo dives put data in every corner: the room for the legend is made below the deepest
    // point, never above the surface (no negative depth on the axis)
    let mut yo = LinePlot::new("Yo-yo", "time (min)", "depth (m)");
    yo.y_down = true;
    yo = yo.with(Series::new(
        "yo-yo dives",
        (0..=12)
            .map(|i| (5.0 * i as f64, if i % 2 == 0 { 0.0 } else { 45.0 }))
            .collect(),
    ));
    let svg = yo.to_svg().unwrap();
    let t = placed_texts(&parse_xml(&svg));
    assert!(!t.iter().any(|(s, _, _)| s.starts_with('-')), "{t:?}");
    assert!(t.iter().any(|(s, x, _)| s == "50" && *x < 130.0), "{t:?}");

    // a log x axis: the decades 1, 10, 100, 1000 are equally spaced
    let mut q = LinePlot::new("Fig. 2a", "initial radius R0 (µm)", "final radius (µm)");
    q.log_x = true;
    q.log_y = true;
    q = q.with(Series::new(
        "none",
        (-10..=30)
            .map(|i| {
                let r = 10f64.powf(i as f64 / 10.0);
                (r, 4.6 * r)
            })
            .collect(),
    ));
    let svg = q.to_svg().unwrap();
    let doc = parse_xml(&svg);
    let t = placed_texts(&doc);
    let x_of = |label: &str| {
        t.iter()
            .filter(|(s, x, y)| s == label && *x > 120.0 && *y > 515.0)
            .map(|(_, x, _)| *x)
            .next()
            .unwrap_or_else(|| panic!("no x tick {label}: {t:?}"))
    };
    // the first decade (0.1, whose log10 is not exactly −1 in floating point) is labelled too
    let (z, a, b, c, d) = (
        x_of("0.1"),
        x_of("1"),
        x_of("10"),
        x_of("100"),
        x_of("1000"),
    );
    assert!(b - a > 100.0, "{a} {b}");
    for (p, q, r) in [(z, a, b), (a, b, c), (b, c, d)] {
        assert!(((q - p) - (r - q)).abs() <= 2.0, "{p} {q} {r}");
    }
    // a log x axis with a secondary y axis is refused, not drawn wrong
    let mut r = q.clone();
    r.secondary_y_label = Some("ratio".into());
    r.series
        .push(Series::new("ratio", vec![(1.0, 1.0), (10.0, 2.0)]).on_secondary());
    assert!(matches!(r.to_svg(), Err(PlotError::Invalid { .. })));
}

#[test]
fn legend_stays_off_the_data_and_long_titles_fit() {
    // five triangle waves between 145 and 200 over the whole x range, as the oscillation
    // overlay: every corner of the plotting area holds data
    let mut p = LinePlot::new(
        "Bubble 0 radius under each elasticity law",
        "time (s)",
        "radius (µm)",
    );
    p.distinct = true;
    for k in 0..5 {
        let pts = (0..=600)
            .map(|i| {
                let t = i as f64 * 0.5;
                let phase = (t / 60.0).fract();
                let tri = if phase < 0.5 {
                    1.0 - 2.0 * phase
                } else {
                    2.0 * phase - 1.0
                };
                (t, 145.0 + 55.0 * tri + 0.1 * k as f64)
            })
            .collect();
        p = p.with(Series::new(format!("continuity-of-displacement {k}"), pts));
    }
    let svg = p.to_svg().unwrap();
    let doc = parse_xml(&svg);
    // the legend box: the translucent white rectangle
    let legend = doc
        .descendants()
        .find(|n| n.has_tag_name("rect") && n.attribute("opacity") == Some("0.85"))
        .expect("legend box");
    let num = |a: &str| legend.attribute(a).unwrap().parse::<f64>().unwrap();
    let (x0, y0, w, h) = (num("x"), num("y"), num("width"), num("height"));
    let mut inside = 0;
    let mut points = 0;
    for n in doc.descendants().filter(|n| n.has_tag_name("polyline")) {
        // data lines are 2 px wide; axes and ticks 1 px
        if n.attribute("stroke-width") != Some("2") {
            continue;
        }
        let pts: Vec<(f64, f64)> = n
            .attribute("points")
            .unwrap()
            .split_whitespace()
            .map(|xy| {
                let (x, y) = xy.split_once(',').unwrap();
                (x.parse().unwrap(), y.parse().unwrap())
            })
            .collect();
        // the legend's own glyphs: a horizontal stroke (or its dashes) 24 px long at the
        // left of the box
        let glyph = pts.len() == 2
            && pts[0].1 == pts[1].1
            && pts.iter().all(|p| p.0 >= x0 && p.0 <= x0 + 40.0);
        if glyph {
            continue;
        }
        for (x, y) in pts {
            points += 1;
            if x >= x0 && x <= x0 + w && y >= y0 && y <= y0 + h {
                inside += 1;
            }
        }
    }
    assert!(points > 1000, "{points}");
    assert_eq!(inside, 0, "{inside} data points under the legend");

    // a dive log's long title: set smaller or on two lines, every character kept, each line
    // narrower than the plot at 0.6 em per character (wider than DejaVu Sans' average)
    let title = "Bubble radius: Subsurface dive 2 of repetitive-logged.xml, 2019-06-14 09:12:00, Shearwater Perdix AI — hydrogel-dive";
    let mut q = radius_plot(2);
    q.title = title.into();
    let svg = q.to_svg().unwrap();
    let doc = parse_xml(&svg);
    let lines: Vec<(String, f64)> = doc
        .descendants()
        .filter(|n| {
            n.has_tag_name("text")
                && n.attribute("y")
                    .is_some_and(|y| y.parse::<f64>().unwrap() < 70.0)
        })
        .map(|n| {
            (
                n.text().unwrap().trim().to_string(),
                n.attribute("font-size").unwrap().parse().unwrap(),
            )
        })
        .collect();
    assert!(!lines.is_empty() && lines.len() <= 2, "{lines:?}");
    let joined = lines
        .iter()
        .map(|l| l.0.as_str())
        .collect::<Vec<_>>()
        .join(" ");
    assert_eq!(joined, title);
    for (l, size) in &lines {
        let est = 0.6 * size * l.chars().count() as f64;
        assert!(est <= DEFAULT_SIZE.0 as f64 - 36.0, "{l}: {est} px");
    }
}
