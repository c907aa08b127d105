//! The writer (layout, escaping, atomic files) and the reader's file handling (xi:include,
//! include cycles, unreadable includes, malformed XML), without external data.

use mtlx::{read_file, read_str, write_file, write_string, Document, SourcePos};
use std::path::{Path, PathBuf};

/// A fresh folder under the system temp dir, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> Self {
        use std::sync::atomic::{AtomicU32, Ordering};
        static N: AtomicU32 = AtomicU32::new(0);
        let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.subsec_nanos()).unwrap_or(0);
        let dir = std::env::temp_dir().join(format!(
            "uplift-mtlx-{tag}-{}-{nanos}-{}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }

    fn write(&self, name: &str, text: &str) -> PathBuf {
        let p = self.0.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn entries(&self) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(&self.0).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn file_name(pos: &SourcePos) -> String {
    Path::new(&*pos.file).file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default()
}

// ---------------------------------------------------------------------------------------------
// Writer
// ---------------------------------------------------------------------------------------------

#[test]
fn the_writer_layout_is_exact() {
    let (doc, diags) = read_str(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<materialx version="1.39" colorspace="lin_rec709">
  <!-- comments are not kept -->
  <nodegraph name="NG"><add name="a" type="float"><input name="in1" type="float" value="1" /><input name="in2" type="float" interfacename="x"/></add>
      <output name="out" type="float" nodename="a"></output></nodegraph>
  <surfacematerial type="material" name="M" />
</materialx>"#,
        "layout.mtlx",
    );
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(
        write_string(&doc),
        r#"<?xml version="1.0"?>
<materialx version="1.39" colorspace="lin_rec709">
  <nodegraph name="NG">
    <add name="a" type="float">
      <input name="in1" type="float" value="1" />
      <input name="in2" type="float" interfacename="x" />
    </add>
    <output name="out" type="float" nodename="a" />
  </nodegraph>
  <surfacematerial type="material" name="M" />
</materialx>
"#
    );
}

#[test]
fn an_empty_document_writes_a_self_closing_root() {
    let doc = Document::new(SourcePos::synthetic("code"));
    assert_eq!(write_string(&doc), "<?xml version=\"1.0\"?>\n<materialx version=\"1.39\" />\n");
}

#[test]
fn the_writer_escapes_attribute_values() {
    let mut doc = Document::new(SourcePos::synthetic("code"));
    let root = doc.root();
    let tricky = "a & b < c > d \"quoted\" 'single'\ttab\nnewline\r\u{85}next-line é 漢字";
    let node = doc.add_child(
        root,
        "image",
        vec![("name".into(), "img".into()), ("type".into(), "color3".into())],
        SourcePos::synthetic("code"),
    );
    doc.add_child(
        node,
        "input",
        vec![
            ("name".into(), "file".into()),
            ("type".into(), "filename".into()),
            ("value".into(), tricky.into()),
            ("doc".into(), "bell\u{7}nul\u{0}".into()),
        ],
        SourcePos::synthetic("code"),
    );
    let text = write_string(&doc);
    assert!(
        text.contains(
            "value=\"a &amp; b &lt; c &gt; d &quot;quoted&quot; 'single'&#x9;tab&#xA;newline&#xD;&#x85;next-line é 漢字\""
        ),
        "{text}"
    );
    // Characters XML 1.0 cannot carry at all become U+FFFD, so the text still parses.
    assert!(text.contains("doc=\"bell\u{fffd}nul\u{fffd}\""), "{text}");
    let (again, diags) = read_str(&text, "escaped.mtlx");
    assert!(diags.is_empty(), "{diags:?}");
    let input = again.children(again.children(again.root())[0])[0];
    assert_eq!(again.get(input).attr("value"), Some(tricky));
    assert_eq!(again.get(input).attr("doc"), Some("bell\u{fffd}nul\u{fffd}"));
    assert_eq!(mtlx::writer::escape_attribute("<UDIM>"), "&lt;UDIM&gt;");
}

#[test]
fn write_file_replaces_the_target_atomically() {
    let dir = TempDir::new("write");
    let target = dir.0.join("out.mtlx");
    let (doc, _) = read_str(r#"<materialx version="1.39"><add name="a" type="float" /></materialx>"#, "a.mtlx");
    write_file(&doc, &target).unwrap();
    assert_eq!(std::fs::read_to_string(&target).unwrap(), write_string(&doc));

    // Overwriting an existing file leaves only the new content, and no temporary files.
    let (doc2, _) = read_str(r#"<materialx version="1.39"><multiply name="m" type="float" /></materialx>"#, "b.mtlx");
    write_file(&doc2, &target).unwrap();
    let (back, diags) = read_file(&target);
    assert!(diags.is_empty(), "{diags:?}");
    assert!(back.same_content(&doc2));
    assert_eq!(dir.entries(), ["out.mtlx"]);

    // Failures report an error and leave nothing behind: a missing folder, a folder as target.
    assert!(write_file(&doc, &dir.0.join("no/such/folder/x.mtlx")).is_err());
    std::fs::create_dir(dir.0.join("sub")).unwrap();
    assert!(write_file(&doc, &dir.0.join("sub")).is_err());
    assert_eq!(dir.entries(), ["out.mtlx", "sub"]);
    assert!(std::fs::read_dir(dir.0.join("sub")).unwrap().next().is_none());
    assert_eq!(std::fs::read_to_string(&target).unwrap(), write_string(&doc2));
}

#[test]
fn upgraded_documents_write_as_1_39_and_read_back_unchanged() {
    let (doc, _) = read_str(
        r#"<materialx version="1.37">
  <swizzle name="s" type="color3"><input name="in" type="color3" value="1, 2, 3" /><parameter name="channels" type="string" value="bgr" /></swizzle>
  <material name="M"><shaderref name="SR" node="standard_surface"><bindinput name="base" type="float" value="0.5" /></shaderref></material>
</materialx>"#,
        "old.mtlx",
    );
    let text = write_string(&doc);
    assert!(text.starts_with("<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n"), "{text}");
    let (again, diags) = read_str(&text, "new.mtlx");
    assert!(diags.is_empty(), "{diags:?}");
    assert!(again.same_content(&doc));
    assert_eq!(write_string(&again), text);
}

// ---------------------------------------------------------------------------------------------
// Reader: includes and errors
// ---------------------------------------------------------------------------------------------

#[test]
fn xi_include_merges_a_sibling_file() {
    let dir = TempDir::new("include");
    dir.write(
        "lib.mtlx",
        r#"<?xml version="1.0"?>
<materialx version="1.38" colorspace="acescg">
  <constant name="shared" type="color3">
    <input name="value" type="color3" value="0.5, 0.5, 0.5" />
  </constant>
  <atan2 name="angle" type="float">
    <input name="in1" type="float" value="1" />
  </atan2>
</materialx>"#,
    );
    let main = dir.write(
        "main.mtlx",
        r#"<?xml version="1.0"?>
<materialx version="1.39" xmlns:xi="http://www.w3.org/2001/XInclude">
  <xi:include href="lib.mtlx" />
  <constant name="local" type="color3" />
</materialx>"#,
    );
    let (doc, diags) = read_file(&main);
    assert!(diags.is_empty(), "{diags:?}");
    let names: Vec<(String, String)> = doc
        .top_level()
        .iter()
        .map(|&e| (doc.get(e).category.clone(), doc.get(e).name().to_string()))
        .collect();
    assert_eq!(
        names,
        [
            ("constant".to_string(), "shared".to_string()),
            ("atan2".to_string(), "angle".to_string()),
            ("constant".to_string(), "local".to_string()),
        ]
    );
    // The included document was upgraded from 1.38 (atan2 in1 → iny) before merging, and its
    // root colorspace went onto the elements it contributed.
    let shared = doc.top_level()[0];
    assert_eq!(doc.get(shared).attr("colorspace"), Some("acescg"));
    let angle = doc.top_level()[1];
    assert_eq!(doc.get(doc.children(angle)[0]).name(), "iny");
    // Positions name the file each element came from.
    assert_eq!(file_name(&doc.get(shared).pos), "lib.mtlx");
    assert_eq!((doc.get(shared).pos.line, doc.get(shared).pos.column), (3, 3));
    let local = doc.top_level()[2];
    assert_eq!(file_name(&doc.get(local).pos), "main.mtlx");
    assert_eq!(doc.get(doc.root()).attr("version"), Some("1.39"));
    // The merged document writes without the include and reads back the same.
    let text = write_string(&doc);
    assert!(!text.contains("include"), "{text}");
    assert!(read_str(&text, "merged.mtlx").0.same_content(&doc));
}

/// MaterialX's reader (XmlIo.cpp `documentFromXml`) imports every xi:include first, then reads
/// the document's own children and skips those whose name is already taken: included elements
/// come first and win name conflicts, and no two siblings share a name. uplift does the same,
/// and says so with a warning at the skipped element.
#[test]
fn xi_include_conflicts_resolve_as_materialx_does() {
    let dir = TempDir::new("conflict");
    dir.write("lib.mtlx", r#"<materialx version="1.39"><constant name="local" type="float" /><constant name="only_lib" type="float" /></materialx>"#);
    let main = dir.write(
        "main.mtlx",
        r#"<materialx version="1.39" xmlns:xi="http://www.w3.org/2001/XInclude">
  <constant name="first" type="float" />
  <xi:include href="lib.mtlx" />
  <constant name="local" type="color3" />
</materialx>"#,
    );
    let (doc, diags) = read_file(&main);
    assert_eq!(diags.len(), 1, "{diags:?}");
    assert!(!diags[0].is_error() && diags[0].message.contains("`local`"), "{diags:?}");
    assert_eq!((diags[0].pos.line, diags[0].pos.column), (4, 3));
    let names: Vec<(&str, Option<&str>)> =
        doc.top_level().iter().map(|&e| (doc.get(e).name(), doc.get(e).attr("type"))).collect();
    assert_eq!(names, [("local", Some("float")), ("only_lib", Some("float")), ("first", Some("float"))]);
}

#[test]
fn an_include_cycle_is_a_positioned_error() {
    let dir = TempDir::new("cycle");
    let main = dir.write(
        "main.mtlx",
        "<materialx version=\"1.39\">\n  <xi:include xmlns:xi=\"http://www.w3.org/2001/XInclude\" href=\"other.mtlx\" />\n</materialx>",
    );
    dir.write(
        "other.mtlx",
        "<materialx version=\"1.39\">\n  <add name=\"a\" type=\"float\" />\n    <xi:include xmlns:xi=\"http://www.w3.org/2001/XInclude\" href=\"main.mtlx\" />\n</materialx>",
    );
    let (doc, diags) = read_file(&main);
    assert_eq!(diags.len(), 1, "{diags:?}");
    let d = &diags[0];
    assert!(d.is_error());
    assert_eq!(file_name(&d.pos), "other.mtlx");
    assert_eq!((d.pos.line, d.pos.column), (3, 5));
    assert!(d.message.contains("cycle") && d.message.contains("main.mtlx"), "{d}");
    // What could be read is still there.
    assert_eq!(doc.top_level().len(), 1);

    // A document including itself.
    let selfish =
        dir.write("self.mtlx", "<materialx version=\"1.39\">\n <xi:include xmlns:xi=\"http://www.w3.org/2001/XInclude\" href=\"self.mtlx\"/>\n</materialx>");
    let (_, diags) = read_file(&selfish);
    assert_eq!(diags.len(), 1, "{diags:?}");
    assert!(diags[0].is_error() && diags[0].message.contains("cycle"));
    assert_eq!((file_name(&diags[0].pos).as_str(), diags[0].pos.line, diags[0].pos.column), ("self.mtlx", 2, 2));
}

#[test]
fn an_unreadable_include_is_a_positioned_error_naming_the_file() {
    let dir = TempDir::new("missing");
    let main = dir.write(
        "main.mtlx",
        "<materialx version=\"1.39\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n  <add name=\"a\" type=\"float\" />\n  <xi:include href=\"missing_library.mtlx\" />\n</materialx>",
    );
    let (doc, diags) = read_file(&main);
    assert_eq!(diags.len(), 1, "{diags:?}");
    let d = &diags[0];
    assert!(d.is_error());
    assert_eq!(file_name(&d.pos), "main.mtlx");
    assert_eq!((d.pos.line, d.pos.column), (3, 3));
    assert!(d.message.contains("missing_library.mtlx"), "{d}");
    assert!(d.to_string().contains("main.mtlx:3:3: error:"), "{d}");
    assert_eq!(doc.top_level().len(), 1, "the rest of the document is still read");
}

#[test]
fn malformed_xml_is_an_error_with_line_and_column() {
    let (doc, diags) = read_str(
        "<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n  <add name=\"a\" type=\"float\">\n</materialx>\n",
        "broken.mtlx",
    );
    assert_eq!(diags.len(), 1, "{diags:?}");
    let d = &diags[0];
    assert!(d.is_error());
    assert_eq!(&*d.pos.file, "broken.mtlx");
    // Reported at the element left open, naming where the mismatching close tag was found.
    assert_eq!((d.pos.line, d.pos.column), (3, 3));
    assert!(d.to_string().starts_with("broken.mtlx:3:3: error: malformed XML: <add> is never closed (found </materialx> at 4:1)"), "{d}");
    assert!(doc.top_level().is_empty());

    // The same for a file, and for a root that is not <materialx>.
    let dir = TempDir::new("malformed");
    let p = dir.write("bad.mtlx", "<materialx version=\"1.39\">\n  <add name=\"a\" type=\"float\" value=\"1\" value=\"2\" />\n</materialx>");
    let (_, diags) = read_file(&p);
    assert_eq!(diags.len(), 1, "{diags:?}");
    assert!(diags[0].is_error());
    assert_eq!(file_name(&diags[0].pos), "bad.mtlx");
    assert_eq!(diags[0].pos.line, 2);
    assert!(diags[0].pos.column > 1);

    let (_, diags) = read_str("<mtlx version=\"1.39\" />", "wrong_root.mtlx");
    assert_eq!(diags.len(), 1, "{diags:?}");
    assert!(diags[0].is_error() && diags[0].message.contains("<mtlx>"), "{:?}", diags[0]);
    assert_eq!((diags[0].pos.line, diags[0].pos.column), (1, 1));
}

#[test]
fn a_missing_file_is_an_error_naming_it() {
    let dir = TempDir::new("nofile");
    let p = dir.0.join("absent.mtlx");
    let (doc, diags) = read_file(&p);
    assert_eq!(diags.len(), 1, "{diags:?}");
    assert!(diags[0].is_error() && diags[0].message.contains("absent.mtlx"), "{:?}", diags[0]);
    assert!(doc.top_level().is_empty());
}

/// MaterialX's namespaced names read as pugixml reads them: `<site_ops:mynoise>` is one
/// category (the prefix is never declared as an XML namespace), positions are where the text
/// puts them, a prefixed attribute keeps its prefix, and the writer writes them back unchanged.
#[test]
fn namespaced_names_read_and_write_back() {
    let text = "<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n  <nodegraph name=\"g\">\n    <site_ops:mynoise name=\"mn1\" type=\"color3\" uplift:encoding=\"sqrt\">\n      <input name=\"f\" type=\"float\" value=\"0.3\"/>\n    </site_ops:mynoise>\n    <output name=\"out\" type=\"color3\" nodename=\"mn1\"/>\n  </nodegraph>\n</materialx>\n";
    let (doc, diags) = read_str(text, "ns.mtlx");
    assert!(diags.is_empty(), "{diags:?}");
    let g = doc.top_level()[0];
    let node = doc.get(doc.children(g)[0]);
    assert_eq!(node.category, "site_ops:mynoise");
    assert_eq!(node.attr("uplift:encoding"), Some("sqrt"));
    assert_eq!((node.pos.line, node.pos.column), (4, 5), "the node's position");
    let (again, diags) = read_str(&write_string(&doc), "again.mtlx");
    assert!(diags.is_empty(), "{diags:?}");
    assert!(again.same_content(&doc), "written and read back:\n{}", write_string(&again));
    assert!(write_string(&doc).contains("<site_ops:mynoise name=\"mn1\""));
}

/// An included document's `namespace` qualifies the names it defines (`ns:name`, as
/// MaterialX's `importLibrary` does), and references resolve as MaterialX resolves them:
/// qualified by the referencing element's namespace first, then as written.
#[test]
fn an_included_namespace_qualifies_its_names() {
    let dir = TempDir::new("namespace");
    dir.write("lib.mtlx", "<materialx version=\"1.39\" namespace=\"stdmaterials\">\n  <nodedef name=\"ND_wood\" node=\"wood\"><output name=\"out\" type=\"float\"/></nodedef>\n  <surfacematerial name=\"plastic\" type=\"material\"/>\n</materialx>\n");
    let main = dir.write(
        "main.mtlx",
        "<materialx version=\"1.39\">\n  <xi:include href=\"lib.mtlx\"/>\n  <surfacematerial name=\"plastic\" type=\"material\"/>\n</materialx>\n",
    );
    let (doc, diags) = read_file(&main);
    assert!(diags.is_empty(), "{diags:?}");
    let names: Vec<&str> = doc.top_level().iter().map(|&c| doc.get(c).name()).collect();
    assert_eq!(names, ["stdmaterials:ND_wood", "stdmaterials:plastic", "plastic"], "no clash between the namespaced and the global `plastic`");
    let nd = doc.top_level()[0];
    assert_eq!(doc.namespace(nd), Some("stdmaterials"));
    assert_eq!(doc.qualified_name(nd, "ND_wood"), "stdmaterials:ND_wood", "already qualified: not twice");
    let root = doc.root();
    assert_eq!(doc.resolve(nd, root, "plastic"), Some(doc.top_level()[1]), "from inside the namespace, the namespaced one");
    assert_eq!(doc.resolve(root, root, "plastic"), Some(doc.top_level()[2]), "from the global scope, the global one");
    assert_eq!(doc.resolve(root, root, "stdmaterials:plastic"), Some(doc.top_level()[1]));
    // A namespaced nodedef read in place keeps its name; `ns:name` still finds it.
    let (doc, _) = read_str("<materialx version=\"1.39\"><nodedef name=\"ND_s\" node=\"s\" namespace=\"mine\"/></materialx>", "x.mtlx");
    let root = doc.root();
    assert_eq!(doc.resolve(root, root, "mine:ND_s"), Some(doc.top_level()[0]));
    assert_eq!(doc.resolve(root, root, "other:ND_s"), None);
}
