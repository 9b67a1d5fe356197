//! Every figure the demo writes renders: a reduced demo (the same report on grids 2× coarser)
//! is written, and each SVG file, and each SVG inlined in report.html, is parsed and drawn to
//! PNG by `resvg` (an SVG renderer independent of plotters, which wrote them); a broken or
//! blank SVG fails. The report's tables print numbers without exponent notation in their
//! natural unit, and the oscillation headline reports growth above R0.

use crate::common::tempdir;
use decophantom::app::demo::{run_sized, DemoSize};
use resvg::{tiny_skia, usvg};
use std::path::{Path, PathBuf};

fn svgs(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            svgs(&p, out);
        } else if p.extension().is_some_and(|x| x == "svg") {
            out.push(p);
        }
    }
}

/// Parse and render one SVG document to PNG bytes; panics (naming `what`) if it does not
/// parse, has no size, or draws nothing but the white background.
fn render(svg: &str, what: &str) -> Vec<u8> {
    let tree = usvg::Tree::from_str(svg, &usvg::Options::default())
        .unwrap_or_else(|e| panic!("{what}: not a valid SVG: {e}"));
    let size = tree.size().to_int_size();
    assert!(
        size.width() >= 300 && size.height() >= 200,
        "{what}: {size:?}"
    );
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height()).unwrap();
    resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
    // the plot lines, axes and bars: a few per cent of the pixels are neither white nor empty
    let inked = pixmap
        .pixels()
        .iter()
        .filter(|p| p.alpha() > 0 && (p.red() < 200 || p.green() < 200 || p.blue() < 200))
        .count();
    let total = (size.width() * size.height()) as usize;
    assert!(
        inked * 100 > total,
        "{what}: only {inked} of {total} pixels drawn"
    );
    pixmap.encode_png().unwrap()
}

#[test]
fn every_svg_of_a_reduced_demo_renders_to_png() {
    let d = tempdir("figures");
    let out = d.join("demo");
    run_sized(&out, DemoSize::REDUCED, &mut |_, _| {}).expect("reduced demo");
    let mut files = Vec::new();
    svgs(&out, &mut files);
    files.sort();
    let names: Vec<String> = files
        .iter()
        .map(|p| p.strip_prefix(&out).unwrap().display().to_string())
        .collect();
    // the demo's figures: dive (profiles, pressure, criteria, volume, 4 radius, area,
    // area-rate, supersaturation, 4 elasticity), oscillation (2 + overlay) and Fig. 2a
    for want in [
        "profiles.svg",
        "pressure.svg",
        "criteria.svg",
        "volume.svg",
        "radius-4.svg",
        "area.svg",
        "area-rate.svg",
        "supersaturation.svg",
        "elasticity-4.svg",
        "elasticity-oscillation.svg",
        "elasticity-fig2a.svg",
        "oscillation/radius.svg",
        "oscillation/volume.svg",
    ] {
        assert!(names.iter().any(|n| n == want), "{want} missing: {names:?}");
    }
    assert_eq!(files.len(), 19, "{names:?}");
    let png_dir = d.join("png");
    std::fs::create_dir_all(&png_dir).unwrap();
    for (f, name) in files.iter().zip(&names) {
        let png = render(&std::fs::read_to_string(f).unwrap(), name);
        std::fs::write(png_dir.join(name.replace('/', "_") + ".png"), png).unwrap();
    }
    // the same figures inlined in the self-contained HTML
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    let mut inline = 0;
    let mut rest = html.as_str();
    while let Some(a) = rest.find("<svg") {
        let b = rest[a..].find("</svg>").expect("unclosed <svg>") + a + "</svg>".len();
        render(&rest[a..b], &format!("report.html figure {}", inline + 1));
        inline += 1;
        rest = &rest[b..];
    }
    assert_eq!(
        inline, 18,
        "report.html inlines every figure but the oscillation volume"
    );
    // numbers in HTML tables do not break across lines
    assert!(html.contains("td.num{") && html.contains("white-space:nowrap"));

    // tables: numbers in their natural unit, no `9.038e1`-style exponents
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    for line in md.lines().filter(|l| l.starts_with('|')) {
        for cell in line.split('|').map(str::trim) {
            let exp = cell.contains('e') && cell.parse::<f64>().is_ok();
            assert!(!exp, "exponent notation in a table cell '{cell}': {line}");
        }
    }
    // one unit system: volumes in mm³ (no m³), and no "max radius … t = 0.0 s" headline
    assert!(!md.contains(" m³"), "a volume in m³ in report.md");
    assert!(
        !md.contains("max radius"),
        "headline reports the start radius"
    );
    assert!(md.contains("no bubble grew above its starting radius R0"));
}
