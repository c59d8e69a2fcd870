//! Probe of the merge tree on a population and its nuisance variants (development tool):
//! `cargo run --release --example tree_probe -- INPUT [--ratio 4] [--count N]`
//! INPUT: a folder of mesh files or synth:PRESET:VERTICES:POSES:SEED.
use posemfa::metrics::adjusted_rand_index;
use posemfa::parts::merge_tree::MergeTree;
use posemfa::parts::robustness::Variant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let input = args.first().expect("INPUT").clone();
    let get = |name: &str| args.iter().position(|a| a == name).map(|i| args[i + 1].parse::<f64>().unwrap());
    let ratio = get("--ratio").unwrap_or(4.0);
    let count = get("--count").map(|c| c as usize);
    let pop = if let Some(rest) = input.strip_prefix("synth:") {
        let f: Vec<&str> = rest.split(':').collect();
        let preset = serde_json::from_value(serde_json::json!(f[0])).unwrap();
        let spec = posemfa::synth::Spec {
            preset,
            vertices: f.get(1).map_or(3000, |v| v.parse().unwrap()),
            poses: f.get(2).map_or(10, |v| v.parse().unwrap()),
            seed: f.get(3).map_or(0, |v| v.parse().unwrap()),
            ..Default::default()
        };
        posemfa::synth::generate(&spec).unwrap().population
    } else {
        posemfa::mesh::Population::new(posemfa::mesh::Sources::paths(&[input.clone()])).unwrap()
    };
    let floor = posemfa::mfa::Params::default().variance_floor;
    let mut labels = Vec::new();
    for v in [Variant::Seed(0), Variant::Reversed, Variant::DropFirst, Variant::DropMiddle, Variant::Moved] {
        let p = v.apply(&pop).unwrap();
        let t0 = std::time::Instant::now();
        let tree = MergeTree::build(&p, floor);
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let k = tree.decided_count(ratio);
        let shown = count.unwrap_or(k);
        if v == Variant::Seed(0) {
            let at = tree.merges.iter().position(|m| m.parts <= 60).unwrap_or(0);
            for m in &tree.merges[at..] {
                println!("  parts {:>3} rise {:.3e} score {:.2}", m.parts, m.rise, m.score);
            }
        }
        let l = tree.labels_at(shown);
        let s0 = tree.typical;
        let mut cuts = Vec::new();
        for c in [4.0, 8.0, 16.0, 32.0, 64.0] {
            let mut cut = tree.counts().1;
            let mut height = 0.0f64;
            for m in &tree.merges {
                height = height.max(m.rise);
                if height >= c * s0 {
                    cut = m.parts;
                    break;
                }
            }
            cuts.push(cut);
        }
        println!(
            "{:<16} leaves {} decided {k} ({ms:.0} ms) s0 {s0:.2e} cuts(4,8,16,32,64) {cuts:?}",
            v.name(),
            tree.n_leaves
        );
        labels.push(l);
    }
    for a in 0..labels.len() {
        let row: Vec<String> =
            (0..labels.len()).map(|b| format!("{:.3}", adjusted_rand_index(&labels[a], &labels[b]))).collect();
        println!("{}", row.join(" "));
    }
}
