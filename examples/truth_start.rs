//! Probe (development tool): does the model prefer a population's truth partition? Fits AECM from the truth's
//! labels (and that fit's vertices then labelled by rigid motion, as the pipeline's last labels are), then the
//! default pipeline (its own count, then the truth's count with `--bones`), and prints each one's parts, final
//! log-likelihood, RMSE and adjusted Rand index against the truth.
//! `cargo run --release --example truth_start -- INPUT TRUTH.json` (TRUTH: one label per vertex, e.g. a skinned
//! character's `truth.json` from `scripts/fixtures/skinned_character.py`).
use posemfa::metrics::adjusted_rand_index;
use posemfa::mfa::{aecm::Fit, data::Data, Params};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(input), Some(truth)) = (args.first(), args.get(1)) else {
        eprintln!("usage: truth_start INPUT TRUTH.json");
        std::process::exit(2);
    };
    let pop = posemfa::mesh::Population::new(posemfa::mesh::Sources::paths(std::slice::from_ref(input)))
        .unwrap_or_else(|e| {
            eprintln!("{input}: {e}");
            std::process::exit(1);
        });
    let truth: Vec<u32> =
        std::fs::read_to_string(truth).ok().and_then(|t| serde_json::from_str(&t).ok()).unwrap_or_else(|| {
            eprintln!("{truth}: not a JSON array of labels");
            std::process::exit(1);
        });
    if truth.len() != pop.n_vertices() {
        eprintln!("{} labels for {} vertices", truth.len(), pop.n_vertices());
        std::process::exit(1);
    }
    let truth = posemfa::parts::labels::compact(&truth);
    let params = Params::default();
    let mut fit = Fit::from_labels(Data::from_population(&pop), &truth, &params).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(1);
    });
    let info = fit.run(&mut |_| true);
    let m = fit.model();
    println!(
        "AECM from the truth: {} parts, log-likelihood {:.1}, {} iterations, RMSE {:.5}, adjusted Rand vs truth {:.3}",
        m.n_parts(),
        info.log_likelihood,
        m.iterations,
        m.rmse(&pop),
        adjusted_rand_index(&m.labels, &truth)
    );
    let mut ml = m.clone();
    let moved = posemfa::parts::motion_labels::label_by_motion(&mut ml, &pop);
    println!(
        "  then labelled by motion ({moved} vertices moved): {} parts, adjusted Rand vs truth {:.3}",
        ml.n_parts(),
        adjusted_rand_index(&ml.labels, &truth)
    );
    for target in [None, Some(m.n_parts())] {
        let params = Params { target_parts: target, ..params.clone() };
        let r = posemfa::parts::hierarchy::fit(&pop, &params, &mut |_| true).unwrap_or_else(|e| {
            eprintln!("{e}");
            std::process::exit(1);
        });
        println!(
            "pipeline ({}): {} parts, log-likelihood {:.1}, RMSE {:.5}, adjusted Rand vs truth {:.3}",
            target.map_or("auto".to_string(), |n| format!("--bones {n}")),
            r.model.n_parts(),
            r.model.log_likelihood.last().copied().unwrap_or(f64::NAN),
            r.model.rmse(&pop),
            adjusted_rand_index(&r.model.labels, &truth)
        );
    }
}
