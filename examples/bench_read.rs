//! Reading speed: `cargo run --release --example bench_read -- DIR_OR_FILES... [--repeat N] [--population]`.
//! Prints JSON: files, bytes, and per repeat the time to read every file into poses with the reader its
//! extension calls for (`mesh::load`: OBJ, PLY, glTF, point caches; no population checks or unit box), or with
//! `--population` the time of `Population::read` of the files (reading, the population's checks and the unit box: what
//! the page's `new Population(names, files)` runs; scripts/bench-read-wasm.mjs compares the two).
//!
//! `--write FORMAT DIR` instead reads the input as a population and writes it, in its original units, as
//! FORMAT into DIR (created; files already there are kept): `obj` (one file per pose), `ply-ascii` (doubles,
//! bit for bit), `ply` (binary little endian, float32), `pc2` or `mdd` (float32, one cache plus `base.obj`
//! with the faces), `glb` (one file: the first pose as the mesh, every other pose as a morph target, animated
//! one key per pose; `export::morph_glb`). Then prints {format, files, bytes}. bench-read-wasm.mjs --formats
//! uses it to time every reader on the same poses.
use std::time::Instant;

fn read_inputs(paths: &[std::path::PathBuf]) -> Result<Vec<(String, Vec<u8>)>, String> {
    let mut files = Vec::new();
    for p in paths {
        let read = |p: &std::path::Path| std::fs::read(p).map_err(|e| format!("cannot read {}: {e}", p.display()));
        if p.is_dir() {
            let mut entries: Vec<_> = std::fs::read_dir(p)
                .map_err(|e| format!("cannot list {}: {e}", p.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_file())
                .collect();
            entries.sort();
            entries.retain(|e| e.extension().is_some_and(|x| x != "mtl"));
            for e in entries {
                files.push((e.file_name().unwrap_or_default().to_string_lossy().into_owned(), read(&e)?));
            }
        } else {
            files.push((p.file_name().unwrap_or_default().to_string_lossy().into_owned(), read(p)?));
        }
    }
    if files.is_empty() {
        return Err("no input files (give folders or files)".into());
    }
    Ok(files)
}

/// The population of `files` written as `format`: (file name, bytes).
fn convert(files: Vec<(String, Vec<u8>)>, format: &str) -> Result<Vec<(String, Vec<u8>)>, String> {
    use posemfa::export::ply::{write_ply, PlyFormat};
    let pop = posemfa::mesh::Population::new(posemfa::mesh::Sources::Files(files)).map_err(|e| e.to_string())?;
    let poses: Vec<Vec<[f64; 3]>> =
        pop.shapes().map(|s| s.iter().map(|p| pop.normalization.to_original(p)).collect()).collect();
    let stem = |n: &str| n.rsplit_once('.').map_or(n, |(s, _)| s).to_string();
    let base = || {
        (
            "base.obj".to_string(),
            posemfa::export::obj::write_obj(&poses[0], &pop.faces, "faces for the cache (pose 1)").into_bytes(),
        )
    };
    Ok(match format {
        "obj" => pop
            .names
            .iter()
            .zip(&poses)
            .map(|(n, s)| (format!("{}.obj", stem(n)), posemfa::export::obj::write_obj(s, &pop.faces, n).into_bytes()))
            .collect(),
        "ply-ascii" | "ply" => {
            let fmt = if format == "ply" { PlyFormat::Binary } else { PlyFormat::Ascii };
            pop.names
                .iter()
                .zip(&poses)
                .map(|(n, s)| (format!("{}.ply", stem(n)), write_ply(s, &pop.faces, fmt, n)))
                .collect()
        }
        "pc2" => vec![base(), ("poses.pc2".into(), posemfa::mesh::cache::write_pc2(&poses))],
        "mdd" => vec![base(), ("poses.mdd".into(), posemfa::mesh::cache::write_mdd(&poses, 24.0))],
        "glb" => {
            let glb = posemfa::export::morph_glb::write_morph_glb("poses", &pop.names, &poses, &pop.faces)
                .map_err(|e| e.to_string())?;
            vec![("poses.glb".into(), glb)]
        }
        f => return Err(format!("--write takes obj, ply-ascii, ply, pc2, mdd or glb, not '{f}'")),
    })
}

fn run() -> Result<(), String> {
    let mut paths = Vec::new();
    let mut repeat = 5usize;
    let mut population = false;
    let mut write: Option<(String, std::path::PathBuf)> = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--population" {
            population = true;
        } else if a == "--repeat" {
            let v = args.next().ok_or("--repeat needs a number")?;
            repeat = v
                .parse()
                .ok()
                .filter(|&r| r > 0)
                .ok_or(format!("--repeat takes a positive whole number, not '{v}'"))?;
        } else if a == "--write" {
            let (Some(f), Some(d)) = (args.next(), args.next()) else { return Err("--write needs FORMAT DIR".into()) };
            write = Some((f, d.into()));
        } else if a.starts_with("--") {
            return Err(format!("unknown option '{a}' (options: --repeat N, --population, --write FORMAT DIR)"));
        } else {
            paths.push(std::path::PathBuf::from(a));
        }
    }
    let files = read_inputs(&paths)?;
    if let Some((format, dir)) = write {
        let out = convert(files, &format)?;
        std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        let bytes: usize = out.iter().map(|f| f.1.len()).sum();
        for (name, b) in &out {
            std::fs::write(dir.join(name), b).map_err(|e| format!("cannot write {name} in {}: {e}", dir.display()))?;
        }
        println!("{{\"format\": \"{format}\", \"files\": {}, \"bytes\": {bytes}}}", out.len());
        return Ok(());
    }
    let bytes: usize = files.iter().map(|f| f.1.len()).sum();
    let mut parse_ms = Vec::new();
    for _ in 0..repeat {
        let input = files.clone();
        let t = Instant::now();
        if population {
            let p = posemfa::mesh::Population::new(posemfa::mesh::Sources::Files(input)).map_err(|e| e.to_string())?;
            std::hint::black_box(p);
        } else {
            let loaded = posemfa::mesh::load::load(input)
                .map_err(|es| es.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("; "))?;
            std::hint::black_box(loaded);
        }
        parse_ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    parse_ms.sort_by(f64::total_cmp);
    let med = parse_ms[parse_ms.len() / 2];
    println!(
        "{{\"files\": {}, \"bytes\": {bytes}, \"parse_ms\": {parse_ms:?}, \"median_ms\": {med:.1}, \"mb_per_s\": {:.0}}}",
        files.len(),
        bytes as f64 / 1e6 / (med / 1e3)
    );
    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("bench_read: {e}");
        std::process::exit(1);
    }
}
