#[test]
fn dump() {
    for v in ["22", "25", "36", "37", "38"] {
        let p = format!("/work/shared/data/materialx/Materials/TestSuite/stdlib/upgrade/syntax_1_{v}.mtlx");
        let (doc, diags) = mtlx::read_file(std::path::Path::new(&p));
        println!("===== {v}");
        for d in &diags { println!("DIAG {d}"); }
        println!("{}", mtlx::write_string(&doc));
    }
}
