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
    };
    let s = run_demo(&o).unwrap();
    assert_eq!(s.materials, 6);
    assert_eq!(s.table.iter().map(|r| r.kind).collect::<Vec<_>>(), vec![0, 1, 2, 3, 4, 5]);
    assert!(s.table.iter().all(|r| r.count == 1 && r.object.1.is_finite() && r.object.1 >= 0.0 && r.object.1 <= 1.0));
    // The reference stack conserves energy: every reference material passes.
    assert_eq!(s.furnace_reference_passed, 6);
    let html = std::fs::read_to_string(&s.report).unwrap();
    let images: Vec<&str> = html.split("src=\"").skip(1).map(|t| t.split('"').next().unwrap()).collect();
    assert_eq!(images.len(), 24, "four images per material");
    for src in &images {
        let p = out.join("report").join(src);
        assert!(p.is_file(), "{} is missing", p.display());
    }
    // Resuming reuses the enhanced and fitted materials.
    let again = run_demo(&o).unwrap();
    assert_eq!(again.materials, 6);

    let Ok(chromium) = std::env::var("UPLIFT_CHROMIUM") else {
        eprintln!("skipped the Chromium half: UPLIFT_CHROMIUM is not set (.ci/run sets it to Debian's chromium)");
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
    assert!(dom.contains("data-images=\"24\""), "the report's load script did not run or saw another image count: {}", &dom[..dom.len().min(400)]);
    assert!(dom.contains("data-broken-images=\"0\""), "broken images in the report");
    eprintln!("Chromium loaded the report: 24 images, none broken");
    let _ = std::fs::remove_dir_all(&out);
}
