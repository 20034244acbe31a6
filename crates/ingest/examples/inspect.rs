//! Prints what the reader found in each file given: layout and reason, kind, specimen, blocks,
//! warnings, and the `inspect --json` report. `cargo run -p cablab-ingest --example inspect -- FILE...`

use cablab_ingest::{read_path, ReadOptions};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let json = args.iter().any(|a| a == "--json");
    for a in args.iter().filter(|a| *a != "--json") {
        match read_path(std::path::Path::new(a), &ReadOptions::default()) {
            Err(e) => eprintln!("error: {e}"),
            Ok(r) => {
                let p = &r.provenance;
                println!(
                    "{a}\n  format {} ({}) | {} {} {} | kind {} ({})",
                    p.format, p.reason, p.encoding, p.separator, p.decimal, r.kind, r.kind_reason
                );
                println!("  specimen {:?}", r.specimen);
                println!(
                    "  blocks {} main {} rows {}",
                    r.blocks.len(),
                    r.main_block,
                    r.data.height()
                );
                for c in &r.channels {
                    println!(
                        "    {:?} [{}] -> {} x{} {:?}",
                        c.name, c.unit, c.si_unit, c.factor, c.role
                    );
                }
                for w in &r.warnings {
                    println!("  {w}");
                }
                if json {
                    println!("{}", serde_json::to_string_pretty(&r.inspect()).unwrap());
                }
            }
        }
    }
}
