//! The demo's report, `report/index.html`: one self-contained page (inline CSS and SVG plots,
//! images beside it in `img/`) with the per-Type image grids (PBR input, enhanced reference,
//! neural, FLIP map), the Table 1-style FLIP table, the white furnace pass rates and the
//! decoder's training curves. A small inline script counts images that failed to load into
//! `<body data-broken-images>`, which the report's test reads back from headless Chromium.

use uplift_render::evaluation::{MaterialEval, TypeRow, PAPER_TABLE1};
use uplift_render::sampler_error::SamplerRow;
use std::fmt::Write;

/// One material's row of the report.
pub struct ReportMaterial {
    pub eval: MaterialEval,
    /// Image file names under img/.
    pub pbr_image: String,
    pub reference_image: String,
    pub neural_image: String,
    pub flip_image: String,
    pub furnace_reference: bool,
    pub furnace_neural: bool,
    pub furnace_neural_worst: f32,
    pub fit_before: f64,
    pub fit_after: f64,
}

/// Everything the page shows.
pub struct Report {
    pub materials: Vec<ReportMaterial>,
    /// Materials shown again with glints (`uplift enhance --glints`, paper §5.3), on the same
    /// fitted latents.
    pub glints: Vec<TwinMaterial>,
    /// Materials of the coated Types shown again with an iridescent clearcoat (`uplift enhance
    /// --iridescence`), fitted on their own, and their per-Type FLIP table.
    pub iridescent: Vec<TwinMaterial>,
    pub iridescent_table: Vec<TypeRow>,
    /// The sampling decoder's variance reduction per Type, and how it was measured.
    pub sampler_table: Vec<SamplerRow>,
    pub sampler_settings: String,
    /// One material exported as an orbit and projected back (`uplift export`, `uplift project`).
    pub orbit: Option<crate::demo::orbit_section::OrbitSection>,
    pub table: Vec<TypeRow>,
    /// The decoder's training history: (step, loss, loss_f, loss_t, loss_r).
    pub history: Vec<[f64; 5]>,
    pub decoder: String,
    pub settings: String,
    pub seconds: f64,
}

/// A material shown again with an addition (glints, an iridescent coat): the twin's name and
/// the renders.
#[derive(Clone, Debug)]
pub struct TwinMaterial {
    pub name: String,
    pub flip_object: f64,
    pub reference_image: String,
    pub neural_image: String,
    pub flip_image: String,
}

/// Text as HTML: `&`, `<`, `>` and `"` escaped.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// Parses the `history` metadata of a weights file (CSV with a header).
pub fn parse_history(csv: &str) -> Vec<[f64; 5]> {
    csv.lines()
        .skip(1)
        .filter_map(|l| {
            let v: Vec<f64> = l.split(',').filter_map(|x| x.trim().parse().ok()).collect();
            (v.len() >= 5).then(|| [v[0], v[1], v[2], v[3], v[4]])
        })
        .collect()
}

/// An SVG line plot of the training curves (log-scale loss against step).
fn training_plot(history: &[[f64; 5]]) -> String {
    if history.len() < 2 {
        return "<p>No training history in the weights file.</p>".into();
    }
    let (w, h, pad) = (640.0, 300.0, 48.0);
    let max_step = history.last().unwrap()[0].max(1.0);
    let vals = history.iter().flat_map(|r| r[1..].iter().copied()).filter(|v| *v > 0.0);
    let (lo, hi) = vals.fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    let (llo, lhi) = (lo.log10().floor(), hi.log10().ceil().max(lo.log10().floor() + 1.0));
    let x = |s: f64| pad + (w - 2.0 * pad) * s / max_step;
    let y = |v: f64| h - pad - (h - 2.0 * pad) * ((v.max(1e-12).log10() - llo) / (lhi - llo));
    let mut svg = format!("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" role=\"img\" aria-label=\"decoder training curves\">");
    let _ = write!(svg, "<rect x=\"{pad}\" y=\"{pad}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#999\"/>", w - 2.0 * pad, h - 2.0 * pad);
    let mut d = llo;
    while d <= lhi + 1e-9 {
        let yy = y(10f64.powf(d));
        let _ = write!(svg, "<line x1=\"{pad}\" x2=\"{}\" y1=\"{yy:.1}\" y2=\"{yy:.1}\" stroke=\"#ddd\"/><text x=\"{}\" y=\"{:.1}\" font-size=\"11\" text-anchor=\"end\">1e{}</text>", w - pad, pad - 4.0, yy + 4.0, d as i32);
        d += 1.0;
    }
    for k in 0..=4 {
        let s = max_step * k as f64 / 4.0;
        let _ = write!(svg, "<text x=\"{:.1}\" y=\"{}\" font-size=\"11\" text-anchor=\"middle\">{}</text>", x(s), h - pad + 16.0, s as u64);
    }
    let _ = write!(svg, "<text x=\"{}\" y=\"{}\" font-size=\"12\" text-anchor=\"middle\">step</text>", w / 2.0, h - 8.0);
    let series = [(1, "#222", "Eq. 3 total"), (2, "#d62728", "f (log1p μl·f)"), (3, "#1f77b4", "T"), (4, "#2ca02c", "R")];
    for (i, (col, color, label)) in series.iter().enumerate() {
        let pts: Vec<String> = history.iter().map(|r| format!("{:.1},{:.1}", x(r[0]), y(r[*col]))).collect();
        let _ = write!(svg, "<polyline fill=\"none\" stroke=\"{color}\" stroke-width=\"1.2\" points=\"{}\"/>", pts.join(" "));
        let ly = pad + 14.0 + 14.0 * i as f64;
        let _ = write!(svg, "<line x1=\"{}\" x2=\"{}\" y1=\"{ly}\" y2=\"{ly}\" stroke=\"{color}\" stroke-width=\"2\"/><text x=\"{}\" y=\"{}\" font-size=\"11\">{label}</text>", w - pad - 150.0, w - pad - 130.0, w - pad - 125.0, ly + 4.0);
    }
    svg + "</svg>"
}

/// The page.
/// A per-Type FLIP table beside the paper's Table 1.
fn type_table(rows: &[TypeRow]) -> String {
    let mut s = String::from("<table><tr><th>Type</th><th>materials</th><th>best</th><th>median</th><th>worst</th><th>full image: best / median / worst</th><th>paper best / median / worst</th><th>median ≤ paper</th></tr>\n");
    for row in rows {
        let p = PAPER_TABLE1.iter().find(|p| p.0 == row.kind).copied().unwrap_or((row.kind, f64::NAN, f64::NAN, f64::NAN));
        let ok = row.object.1 <= p.2;
        let _ = writeln!(
            s,
            "<tr><td>{}</td><td>{}</td><td>{:.4}</td><td>{:.4}</td><td>{:.4}</td><td>{:.4} / {:.4} / {:.4}</td><td>{:.4} / {:.4} / {:.4}</td><td class=\"{}\">{}</td></tr>",
            row.kind, row.count, row.object.0, row.object.1, row.object.2, row.full.0, row.full.1, row.full.2, p.1, p.2, p.3,
            if ok { "pass" } else { "fail" }, if ok { "yes" } else { "no" }
        );
    }
    s += "</table>\n";
    s
}

/// The sampling decoder's per-Type variance ratios.
pub fn sampler_table(rows: &[SamplerRow]) -> String {
    let mut s = String::from("<table><tr><th>Type</th><th>materials</th><th>lowest</th><th>median</th><th>highest</th><th>below cosine sampling for all</th></tr>\n");
    for row in rows {
        let ok = row.ratio.0 > 1.0;
        let _ = writeln!(
            s,
            "<tr><td>{}</td><td>{}</td><td>{:.2}×</td><td>{:.2}×</td><td>{:.2}×</td><td class=\"{}\">{}</td></tr>",
            row.kind, row.count, row.ratio.0, row.ratio.1, row.ratio.2, if ok { "pass" } else { "fail" }, if ok { "yes" } else { "no" }
        );
    }
    s += "</table>\n";
    s
}

pub fn render_html(r: &Report) -> String {
    let mut s = String::new();
    s += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>uplift demo report</title>\n<style>body{font-family:system-ui,sans-serif;margin:24px;max-width:1200px;color:#222}table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #ccc;padding:4px 8px;text-align:right}th{background:#f4f4f4}td.l,th.l{text-align:left}.grid img{width:160px;height:160px;display:block}.grid td{text-align:center;font-size:12px}.pass{color:#080}.fail{color:#b00}code{background:#f4f4f4;padding:1px 4px}</style></head>\n<body data-broken-images=\"unknown\">\n";
    s += "<h1>uplift demo</h1>\n";
    let _ = writeln!(s, "<p>{}</p>", escape(&r.settings));
    let _ = writeln!(s, "<p>Decoder: <code>{}</code>. Total time {:.0} s.</p>", escape(&r.decoder), r.seconds);
    s += "<h2>FLIP per enhancement Type (paper Table 1 format)</h2>\n<p>Mean LDR-FLIP of reference vs neural preview-ball renders, over the ball's pixels; the whole image's figure beside it. Paper: 50 materials per Type.</p>\n";
    s += &type_table(&r.table);
    let n = r.materials.len().max(1);
    let pass_ref = r.materials.iter().filter(|m| m.furnace_reference).count();
    let pass_neu = r.materials.iter().filter(|m| m.furnace_neural).count();
    s += "<h2>White furnace</h2>\n";
    let _ = writeln!(
        s,
        "<p>Per-texel test (total albedo ∫ f cos dωl + T·c ≤ 1 at every checked texel and view; docs/render.md). Reference: {pass_ref} of {} pass ({:.1} %). Neural: {pass_neu} of {} pass ({:.1} %). Paper: ≈ 90 %.</p>",
        r.materials.len(), 100.0 * pass_ref as f64 / n as f64, r.materials.len(), 100.0 * pass_neu as f64 / n as f64
    );
    s += "<h2>Decoder training curves</h2>\n";
    s += &training_plot(&r.history);
    s += "\n<h2>Materials</h2>\n";
    for kind in 0..6 {
        let of: Vec<&ReportMaterial> = r.materials.iter().filter(|m| m.eval.kind == kind).collect();
        if of.is_empty() {
            continue;
        }
        let _ = writeln!(s, "<h3>Type {kind}</h3>\n<table class=\"grid\"><tr><th class=\"l\">material</th><th>PBR input (base colour | roughness)</th><th>enhanced reference</th><th>neural</th><th>FLIP</th></tr>");
        for m in of {
            let _ = writeln!(
                s,
                "<tr><td class=\"l\">{}<br>FLIP {:.4} (image {:.4})<br>PSNR {:.1} dB<br>fit Eq. 3 {:.4} → {:.4}<br>furnace: reference <span class=\"{}\">{}</span>, neural <span class=\"{}\">{}</span> (worst {:.3})</td><td><img src=\"img/{}\" alt=\"PBR input\"></td><td><img src=\"img/{}\" alt=\"reference\"></td><td><img src=\"img/{}\" alt=\"neural\"></td><td><img src=\"img/{}\" alt=\"FLIP\"></td></tr>",
                escape(&m.eval.name), m.eval.flip_object, m.eval.flip_full, m.eval.psnr_object, m.fit_before, m.fit_after,
                if m.furnace_reference { "pass" } else { "fail" }, if m.furnace_reference { "pass" } else { "fail" },
                if m.furnace_neural { "pass" } else { "fail" }, if m.furnace_neural { "pass" } else { "fail" }, m.furnace_neural_worst,
                escape(&m.pbr_image), escape(&m.reference_image), escape(&m.neural_image), escape(&m.flip_image)
            );
        }
        s += "</table>\n";
    }
    if !r.glints.is_empty() {
        s += "<h2>Glints (paper §5.3)</h2>\n<p>Materials above enhanced again with <code>--glints</code>: the same rule draws, plus an energy-neutral sparkle pattern N tied to the surface on the non-diffuse part (f_nd · N). The neural material reuses its twin's fitted latents unchanged: the renderer applies N to the decoder's output as to the reference stack, so glints need no retraining.</p>\n<table class=\"grid\"><tr><th class=\"l\">material</th><th>reference with glints</th><th>neural with glints</th><th>FLIP</th></tr>\n";
        for g in &r.glints {
            let _ = writeln!(
                s,
                "<tr><td class=\"l\">{}<br>FLIP {:.4}</td><td><img src=\"img/{}\" alt=\"reference with glints\"></td><td><img src=\"img/{}\" alt=\"neural with glints\"></td><td><img src=\"img/{}\" alt=\"FLIP\"></td></tr>",
                escape(&g.name), g.flip_object, escape(&g.reference_image), escape(&g.neural_image), escape(&g.flip_image)
            );
        }
        s += "</table>\n";
    }
    if !r.iridescent.is_empty() {
        s += "<h2>Iridescent clearcoat</h2>\n<p>Every material of the coated Types (2, 3, 5) enhanced again with <code>--iridescence</code>: a thin film on the clearcoat (thickness 100–1000 nm, IOR 1.2–2.0, drawn per material), whose Airy reflectance makes the coat iridescent. The film's two parameters are inputs of the stack, so these materials are fitted on their own against the decoder trained with them.</p>\n";
        s += &type_table(&r.iridescent_table);
        s += "<table class=\"grid\"><tr><th class=\"l\">material</th><th>reference</th><th>neural</th><th>FLIP</th></tr>\n";
        for g in &r.iridescent {
            let _ = writeln!(
                s,
                "<tr><td class=\"l\">{}<br>FLIP {:.4}</td><td><img src=\"img/{}\" alt=\"reference, iridescent\"></td><td><img src=\"img/{}\" alt=\"neural, iridescent\"></td><td><img src=\"img/{}\" alt=\"FLIP\"></td></tr>",
                escape(&g.name), g.flip_object, escape(&g.reference_image), escape(&g.neural_image), escape(&g.flip_image)
            );
        }
        s += "</table>\n";
    }
    if !r.sampler_table.is_empty() {
        let _ = writeln!(
            s,
            "<h2>Sampling decoder (paper §4.1)</h2>\n<p>Every material above, its neural non-diffuse part importance-sampled by the sampling decoder or by the cosine lobe alone, at equal samples per pixel ({}); the ratio of their mean squared errors against the converged render (above 1: the sampling decoder leaves that many times less variance).</p>",
            escape(&r.sampler_settings)
        );
        s += &sampler_table(&r.sampler_table);
    }
    if let Some(o) = &r.orbit {
        let _ = writeln!(
            s,
            "<h2>Data for generative models (paper §5.2)</h2>\n<p><code>uplift export</code>: {} on a UV sphere, an orbit of {} frames per modality (intrinsic buffers from one ray per pixel centre; the shaded frame path traced, Blender's AgX). <code>uplift project</code>: its own latent and base-colour frames back into texture space — {} of {} texels of the UV chart seen by the frames; base colour PSNR {} on them; neural renders (sampling decoder) of the original and the projected material from a new viewpoint differ by FLIP {:.4} over the object.</p>",
            escape(&o.material), o.frames, o.projected_texels, o.chart_texels, if !o.base_color_psnr.is_nan() { format!("{:.1} dB", o.base_color_psnr) } else { "n/a (the projection's texture size differs from the material's)".into() }, o.flip
        );
        s += "<table class=\"grid\">\n";
        for (m, file) in &o.strips {
            let _ = writeln!(s, "<tr><td class=\"l\">{}</td><td><img style=\"width:auto;height:96px\" src=\"img/{}\" alt=\"{} frames\"></td></tr>", escape(m), escape(file), escape(m));
        }
        s += "</table>\n";
        let _ = writeln!(
            s,
            "<table class=\"grid\"><tr><th>original (neural)</th><th>projected back (neural)</th><th>texture coverage</th></tr><tr><td><img src=\"img/{}\" alt=\"original\"></td><td><img src=\"img/{}\" alt=\"projected\"></td><td><img src=\"img/{}\" alt=\"coverage\"></td></tr></table>\n<p>Coverage: green projected, orange inpainted inside the chart, blue gutter.</p>",
            escape(&o.original_image), escape(&o.projected_image), escape(&o.coverage_image)
        );
    }
    s += "<script>window.addEventListener('load',function(){var b=0;for(const i of document.images){if(!i.complete||i.naturalWidth===0)b++;}document.body.dataset.brokenImages=String(b);document.body.dataset.images=String(document.images.length);});</script>\n";
    s += "</body></html>\n";
    s
}
