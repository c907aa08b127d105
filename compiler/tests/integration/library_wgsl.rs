//! The whole WGSL node library, concatenated, parses and validates with naga: a syntax or type
//! error in any library file fails here, naming the file and line.

use std::path::{Path, PathBuf};

fn wgsl_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            wgsl_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "wgsl") {
            out.push(p);
        }
    }
}

#[test]
fn every_library_file_validates_alone_and_together() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../mtlx/libraries");
    let mut files = Vec::new();
    wgsl_files(&root, &mut files);
    assert!(!files.is_empty(), "no WGSL files under {}", root.display());
    let mut all = String::new();
    for f in &files {
        all.push_str(&std::fs::read_to_string(f).unwrap());
        all.push('\n');
    }
    let module = match naga::front::wgsl::parse_str(&all) {
        Ok(m) => m,
        Err(e) => {
            // Re-parse file by file to name the file that fails.
            for f in &files {
                let text = std::fs::read_to_string(f).unwrap();
                if let Err(e) = naga::front::wgsl::parse_str(&text) {
                    let msg = e.emit_to_string(&text);
                    if !msg.contains("no definition in scope") {
                        panic!("{}: {}", f.display(), msg);
                    }
                }
            }
            panic!("library does not parse: {}", e.emit_to_string(&all));
        }
    };
    let mut validator = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all());
    if let Err(e) = validator.validate(&module) {
        panic!("library does not validate: {}", e.emit_to_string(&all));
    }
}
