//! Every .mtlx of MaterialX's test suite and examples: read → write → read gives the same
//! document, and reading reports no errors. Needs `UPLIFT_MTLX_DATA` (the folder holding
//! `Materials/`, e.g. `../shared/data/materialx` from the repository root); skipped without it.

use mtlx::{read_file, read_str, write_string, Diagnostic, Document};
use std::path::{Path, PathBuf};

/// Documents that are expected to produce error diagnostics when read: none. (udim.mtlx writes
/// a raw `<` inside an attribute value, `grid.<UDIM>.png`; the reader accepts it as MaterialX's
/// pugixml does.)
const EXPECTED_ERRORS: &[&str] = &[];

/// Says the test is skipped; under `UPLIFT_REQUIRE_ALL=1` (set by .ci/run) that is a failure
/// (runtime/base/src/test_env.rs has the runtime's copy).
fn skip(reason: &str) {
    assert!(std::env::var_os("UPLIFT_REQUIRE_ALL").is_none_or(|v| v != "1"), "cannot run under UPLIFT_REQUIRE_ALL=1: {reason}");
    eprintln!("skipped: {reason}");
}

fn data_root() -> Option<PathBuf> {
    match std::env::var_os("UPLIFT_MTLX_DATA") {
        Some(v) if !v.is_empty() => {
            let p = PathBuf::from(v);
            // Relative paths are relative to the repository root (cargo runs tests in mtlx/).
            Some(if p.is_relative() { Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(p) } else { p })
        }
        _ => {
            skip("UPLIFT_MTLX_DATA is not set (set it to ../shared/data/materialx; .ci/run does)");
            None
        }
    }
}

/// Appends the `.mtlx` files under `dir`, sorted.
fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    out.extend(mtlx::library::files_under(dir).into_iter().filter(|p| p.extension().is_some_and(|e| e == "mtlx")));
}

/// Constructs that no 1.39 document has: what the upgrade must have removed.
fn legacy_constructs(doc: &Document) -> Vec<String> {
    const LEGACY: [&str; 14] = [
        "parameter", "opgraph", "shader", "shaderref", "material", "bindinput", "bindparam", "bindtoken",
        "override", "materialinherit", "lookinherit", "geomattr", "geomattrvalue", "swizzle",
    ];
    const RENAMED: [&str; 12] = [
        "compare", "combine", "separate", "rotate", "dielectric_brdf", "dielectric_btdf", "conductor_brdf",
        "generalized_schlick_brdf", "sheen_brdf", "diffuse_brdf", "diffuse_btdf", "thin_film_bsdf",
    ];
    let mut out = Vec::new();
    for e in doc.descendants(doc.root()) {
        let el = doc.get(e);
        let what = format!("<{} name=\"{}\"> at {}", el.category, el.name(), el.pos);
        if LEGACY.contains(&el.category.as_str()) || RENAMED.contains(&el.category.as_str()) {
            out.push(format!("legacy element {what}"));
        }
        if el.attr("channels").is_some() {
            out.push(format!("`channels` attribute on {what}"));
        }
        if el.attr("type") == Some("color2") {
            out.push(format!("color2 type on {what}"));
        }
        let parent_is_node = el.parent.is_some_and(|p| {
            let c = doc.get(p).category.as_str();
            !matches!(c, "materialx" | "nodegraph" | "nodedef" | "implementation" | "typedef" | "geominfo" | "look")
        });
        if el.category == "input" && parent_is_node && el.attr("value").is_some()
            && ["nodename", "nodegraph", "interfacename", "output"].iter().any(|k| el.attr(k).is_some())
        {
            out.push(format!("input with both a value and a connection: {what}"));
        }
        if el.category == "atan2" && (doc.child(e, "in1").is_some() || doc.child(e, "in2").is_some()) {
            out.push(format!("atan2 with in1/in2: {what}"));
        }
        if el.category == "normalmap" && doc.child(e, "space").is_some() {
            out.push(format!("normalmap with a space input: {what}"));
        }
    }
    out
}

fn relative(path: &Path, root: &Path) -> String {
    path.strip_prefix(root).unwrap_or(path).display().to_string()
}

#[test]
fn test_suite_and_examples_round_trip() {
    let Some(root) = data_root() else { return };
    let materials = root.join("Materials");
    assert!(materials.is_dir(), "{} is not a folder", materials.display());
    let mut files = Vec::new();
    collect(&materials.join("TestSuite"), &mut files);
    collect(&materials.join("Examples"), &mut files);
    assert!(files.len() > 100, "expected the MaterialX test suite under {}, found {} files", materials.display(), files.len());

    let mut failures = Vec::new();
    let mut with_errors = Vec::new();
    let mut warnings = 0;
    for path in &files {
        let rel = relative(path, &materials);
        let (doc, diags) = read_file(path);
        let errors: Vec<&Diagnostic> = diags.iter().filter(|d| d.is_error()).collect();
        warnings += diags.len() - errors.len();
        if !errors.is_empty() {
            with_errors.push(format!("{rel}:\n{}", errors.iter().map(|d| format!("    {d}\n")).collect::<String>()));
            if !EXPECTED_ERRORS.contains(&rel.as_str()) {
                failures.push(format!("{rel}: unexpected errors"));
            }
        } else if EXPECTED_ERRORS.contains(&rel.as_str()) {
            failures.push(format!("{rel}: expected errors, read cleanly"));
        }
        if doc.get(doc.root()).attr("version") != Some("1.39") {
            failures.push(format!("{rel}: version after reading is {:?}", doc.get(doc.root()).attr("version")));
        }

        failures.extend(legacy_constructs(&doc).into_iter().map(|m| format!("{rel}: {m}")));

        let text = write_string(&doc);
        let (again, diags2) = read_str(&text, &path.display().to_string());
        if diags2.iter().any(Diagnostic::is_error) {
            failures.push(format!("{rel}: re-reading the written text reports errors: {diags2:?}"));
        }
        if !doc.same_content(&again) {
            failures.push(format!("{rel}: read → write → read changed the document"));
        }
        // Writing is deterministic: the re-read document writes the same text.
        if write_string(&again) != text {
            failures.push(format!("{rel}: writing the re-read document gives different text"));
        }
    }
    println!("{} documents read, {} warnings", files.len(), warnings);
    if !with_errors.is_empty() {
        println!("documents with errors:\n{}", with_errors.join(""));
    }
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

/// MaterialX's own node libraries (under `UPLIFT_MTLX_DATA/libraries`) and uplift's
/// (`mtlx/libraries`) round-trip too.
#[test]
fn libraries_round_trip() {
    let mut files = Vec::new();
    collect(&Path::new(env!("CARGO_MANIFEST_DIR")).join("libraries"), &mut files);
    if let Some(root) = data_root() {
        collect(&root.join("libraries"), &mut files);
    }
    let mut failures = Vec::new();
    for path in &files {
        let (doc, diags) = read_file(path);
        if let Some(e) = diags.iter().find(|d| d.is_error()) {
            failures.push(format!("{e}"));
        }
        let text = write_string(&doc);
        let (again, _) = read_str(&text, &path.display().to_string());
        if !doc.same_content(&again) {
            failures.push(format!("{}: read → write → read changed the document", path.display()));
        }
    }
    println!("{} library documents read", files.len());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
