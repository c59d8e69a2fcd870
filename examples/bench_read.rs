//! Reading speed: `cargo run --release --example bench_read -- DIR_OR_FILES... [--repeat N] [--population]`.
//! Prints JSON: files, bytes, and per repeat the time to read every file into poses with the reader its
//! extension calls for (`mesh::load`: OBJ, PLY, glTF, point caches; no population checks or unit box), or with
//! `--population` the time of `Population::from_files` (reading, the population's checks and the unit box: what
//! the page's `new Population(names, files)` runs; scripts/bench-read-wasm.mjs compares the two).
use std::time::Instant;

fn main() {
    let mut paths = Vec::new();
    let mut repeat = 5usize;
    let mut population = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--population" {
            population = true;
        } else if a == "--repeat" {
            repeat = args.next().and_then(|r| r.parse().ok()).unwrap_or(5);
        } else {
            paths.push(std::path::PathBuf::from(a));
        }
    }
    let mut files = Vec::new();
    for p in &paths {
        if p.is_dir() {
            let mut entries: Vec<_> = std::fs::read_dir(p).unwrap().map(|e| e.unwrap().path()).filter(|p| p.is_file()).collect();
            entries.sort();
            entries.retain(|e| e.extension().is_some_and(|x| x != "mtl"));
            for e in entries {
                files.push((e.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read(&e).unwrap()));
            }
        } else {
            files.push((p.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read(p).unwrap()));
        }
    }
    let bytes: usize = files.iter().map(|f| f.1.len()).sum();
    let mut parse_ms = Vec::new();
    for _ in 0..repeat {
        let input = files.clone();
        let t = Instant::now();
        if population {
            let p = posemfa::mesh::Population::from_files(input).unwrap_or_else(|e| panic!("{e}"));
            std::hint::black_box(p);
        } else {
            let loaded = posemfa::mesh::load::load(input).unwrap_or_else(|e| panic!("{e:?}"));
            std::hint::black_box(loaded);
        }
        parse_ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    parse_ms.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let med = parse_ms[parse_ms.len() / 2];
    println!("{{\"files\": {}, \"bytes\": {bytes}, \"parse_ms\": {parse_ms:?}, \"median_ms\": {med:.1}, \"mb_per_s\": {:.0}}}", files.len(), bytes as f64 / 1e6 / (med / 1e3));
}
