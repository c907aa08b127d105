//! `uplift demo` end to end at a tiny size: every stage runs, the report and its images are
//! written, the Table 1 rows cover all six Types, and — with headless Chromium
//! (`UPLIFT_CHROMIUM`, set by .ci/run) — the report renders with no broken images.

use std::path::PathBuf;
use std::process::Command;
use uplift::demo::{run_demo, DemoOptions};

#[test]
fn demo_writes_a_report_that_renders_without_broken_images() {
    let out = std::env::temp_dir().join(format!("uplift-demo-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let o = DemoOptions {
        out: out.clone(),
        decoder: PathBuf::from(uplift_neural::weights::SHIPPED_DECODER),
        per_type: 1,
        texture_size: 16,
        render_size: 32,
        spp: 2,
        fit_steps: 3,
        seed: 5,
        threads: 2,
        sampler_study: uplift_render::sampler_error::SamplerErrorOptions { size: 16, spp: 4, converged_spp: 64, seed: 0 },
    };
    let s = run_demo(&o).unwrap();
    assert_eq!(s.materials, 6);
    assert_eq!(s.table.iter().map(|r| r.kind).collect::<Vec<_>>(), vec![0, 1, 2, 3, 4, 5]);
    assert!(s.table.iter().all(|r| r.count == 1));
    // Every material of the coated Types has an iridescent twin, tabled per Type.
    assert_eq!(s.iridescent_table.iter().map(|r| (r.kind, r.count)).collect::<Vec<_>>(), vec![(2, 1), (3, 1), (5, 1)]);
    // The reference stack conserves energy: every reference material passes; the fit holds the
    // neural materials to the same bound (docs/neural.md), so every neural one passes too.
    assert_eq!(s.furnace_reference_passed, 6);
    assert_eq!(s.furnace_neural_passed, 6);
    let html = std::fs::read_to_string(&s.report).unwrap();
    let images: Vec<&str> = html.split("src=\"").skip(1).map(|t| t.split('"').next().unwrap()).collect();
    assert_eq!(images.len(), 24 + 6 + 9 + 8 + 3, "four images per material, three per glint row (Types 0 and 1) and per iridescent row (Types 2, 3, 5), eight orbit strips and three projection images");
    assert!(html.contains("<h2>Data for generative models (paper §5.2)</h2>"), "no export/projection section");
    assert!(html.contains("<h2>Iridescent clearcoat</h2>"), "no iridescence section");
    assert!(html.contains("<h2>Glints (paper §5.3)</h2>"), "no glint section");
    // The shipped decoder file has a sampling decoder: its study covers every Type.
    assert!(html.contains("<h2>Sampling decoder (paper §4.1)</h2>"), "no sampling-decoder section");
    assert_eq!(s.sampler_table.iter().map(|r| (r.kind, r.count)).collect::<Vec<_>>(), (0..6).map(|k| (k, 1)).collect::<Vec<_>>());
    assert!(s.sampler_table.iter().all(|r| r.ratio.1.is_finite() && r.ratio.1 > 0.0));
    for src in &images {
        let p = out.join("report").join(src);
        assert!(p.is_file(), "{} is missing", p.display());
    }
    // The table's whole-image FLIP, recomputed from the report's own PNGs with the nv-flip crate
    // directly (one material per Type: the median is that material's figure).
    let materials = out.join("materials");
    for row in &s.table {
        let name = std::fs::read_dir(&materials)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .filter(|n| !n.ends_with("_glints") && !n.ends_with("_iridescent"))
            .find(|n| uplift_material::MaterialFolder::open(&materials.join(n)).unwrap().read_meta().unwrap().kind as usize == row.kind)
            .unwrap();
        if [2, 3, 5].contains(&row.kind) {
            // Its iridescent twin: the same rule draws plus a coat film, fitted on its own.
            let twin = uplift_material::MaterialFolder::open(&materials.join(format!("{name}_iridescent"))).unwrap();
            let img = uplift_base::exr::read(&twin.params_path()).unwrap();
            assert!(img.channel("coat_film_thickness").unwrap()[0] >= 100.0, "{name}_iridescent has no film");
            assert!(twin.has_fit(), "{name}_iridescent is not fitted");
        }
        if row.kind <= 1 {
            // Its glint twin: the same parameters and latents, a different (sparkling) image.
            let twin = uplift_material::MaterialFolder::open(&materials.join(format!("{name}_glints"))).unwrap();
            assert!(twin.read_meta().unwrap().glint.is_some(), "{name}_glints records no glints");
            let plain = std::fs::read(out.join("report/img").join(format!("{name}_reference.png"))).unwrap();
            let glinty = std::fs::read(out.join("report/img").join(format!("{name}_glints_reference.png"))).unwrap();
            assert_ne!(plain, glinty, "{name}: glints change nothing in the render");
        }
        let png = |which: &str| image::open(out.join("report/img").join(format!("{name}_{which}.png"))).unwrap().to_rgb8();
        let (r, n) = (png("reference"), png("neural"));
        let (w, h) = r.dimensions();
        let map = nv_flip::flip(nv_flip::FlipImageRgb8::with_data(w, h, &r), nv_flip::FlipImageRgb8::with_data(w, h, &n), nv_flip::pixels_per_degree(0.7, 3840.0, 0.7));
        let mean = map.to_vec().iter().map(|&e| e as f64).sum::<f64>() / (w * h) as f64;
        assert!((mean - row.full.1).abs() <= 1e-6, "Type {}: the table's FLIP {} vs {mean} recomputed from {name}'s images", row.kind, row.full.1);
        assert!(row.object.1 > 0.0 && row.object.1 < 1.0, "Type {}: object FLIP {}", row.kind, row.object.1);
    }
    // Resuming reuses the enhanced and fitted materials: no file of theirs is written again,
    // and the report's table is the same.
    let stamps = |dir: &std::path::Path| -> Vec<(PathBuf, std::time::SystemTime)> {
        let mut v: Vec<_> = std::fs::read_dir(dir).unwrap().flat_map(|m| std::fs::read_dir(m.unwrap().path()).unwrap()).map(|f| f.unwrap()).filter(|f| f.path().is_file()).map(|f| (f.path(), f.metadata().unwrap().modified().unwrap())).collect();
        v.sort();
        v
    };
    let before = stamps(&materials);
    assert!(before.len() >= 6 * 5, "material folders hold {} files", before.len());
    let again = run_demo(&o).unwrap();
    assert_eq!(again.materials, 6);
    assert_eq!(stamps(&materials), before, "resuming wrote a material's files again");
    assert_eq!(format!("{:?}", again.table), format!("{:?}", s.table), "resuming changed the table");

    let Ok(chromium) = std::env::var("UPLIFT_CHROMIUM") else {
        uplift_base::test_env::skip("the demo report in Chromium", "UPLIFT_CHROMIUM is not set (.ci/run sets it to Debian's chromium)");
        let _ = std::fs::remove_dir_all(&out);
        return;
    };
    let profile = out.join("chromium-profile");
    let dom = Command::new(&chromium)
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking", "--disable-component-update", "--disable-sync", "--virtual-time-budget=10000"])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg("--dump-dom")
        .arg(format!("file://{}", s.report.display()))
        .output()
        .expect("chromium runs");
    assert!(dom.status.success(), "chromium failed: {}", String::from_utf8_lossy(&dom.stderr));
    let dom = String::from_utf8_lossy(&dom.stdout);
    assert!(dom.contains("data-images=\"50\""), "the report's load script did not run or saw another image count: {}", &dom[..dom.len().min(400)]);
    assert!(dom.contains("data-broken-images=\"0\""), "broken images in the report");
    eprintln!("Chromium loaded the report: 50 images, none broken");
    let _ = std::fs::remove_dir_all(&out);
}
