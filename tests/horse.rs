//! The figures of the method on the real horse population (data/horse-poses in ../shared or POSEMFA_SHARED).
//! Skipped, counted as skipped, when the data is absent (a failure under CI=true: `common::shared_dir`). The JSON is checked the way a user would: eq 22 recomputed
//! from the written file gives the reported RMSE.

use posemfa::export::json::fit_to_json;
use posemfa::mesh::Population;
use posemfa::mfa::Params;
use posemfa::parts::hierarchy::fit;
use std::path::PathBuf;

mod common;

fn horse(test: &str) -> Option<(PathBuf, Population)> {
    let dir = common::shared_dir("data/horse-poses", test)?;
    let pop = Population::new(posemfa::mesh::Sources::paths(&[&dir])).expect("horse loads");
    Some((dir, pop))
}

#[test]
fn horse_at_defaults_meets_the_figures_and_the_json_is_consistent() {
    let Some((dir, pop)) = horse("horse_at_defaults_meets_the_figures_and_the_json_is_consistent") else { return };
    let result = fit(&pop, &Params::default(), &mut |_| true).unwrap();
    let json: serde_json::Value = serde_json::from_str(&fit_to_json(&pop, &result)).unwrap();
    let parts = json["parts"].as_array().unwrap();
    assert!((20..=34).contains(&parts.len()), "{} parts", parts.len());
    assert_eq!(json["stages"]["final_parts"].as_u64().unwrap() as usize, parts.len());
    let rmse = json["rmse"].as_f64().unwrap();
    assert!(rmse <= 0.004, "rmse {rmse}");
    // every rotation det +1 and orthonormal
    for p in parts {
        for r in p["rotations"].as_array().unwrap() {
            let r: Vec<f64> = r.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
            let m = posemfa::geometry::Mat3::from_row_slice(&r);
            assert!((posemfa::geometry::det(&m) - 1.0).abs() < 1e-9);
            assert!(posemfa::geometry::orthonormality_error(&m) < 1e-9);
        }
    }
    // log-likelihood trace never decreasing
    let ll: Vec<f64> = json["log_likelihood"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    for w in ll.windows(2) {
        assert!(w[1] >= w[0] - 1e-9 * w[0].abs(), "{} -> {}", w[0], w[1]);
    }
    assert!(json["converged"].as_bool().unwrap());
    // eq 22 from the JSON, in unit-box coordinates: shape i vertex j ≈ R^i_{l_j} latent_j + b^i_{l_j}
    let labels = json["labels"].as_array().unwrap();
    let latent = json["latent"].as_array().unwrap();
    let n = json["normalization"].clone();
    let offset: Vec<f64> = n["offset"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let scale = n["scale"].as_f64().unwrap();
    let names: Vec<&str> = json["shapes"].as_array().unwrap().iter().map(|v| v.as_str().unwrap()).collect();
    assert_eq!(names, pop.names.iter().map(String::as_str).collect::<Vec<_>>());
    let mut s = 0.0;
    let mut count = 0usize;
    for (i, name) in names.iter().enumerate() {
        // the original file, moved into the unit box with the JSON's normalisation
        let bytes = std::fs::read(dir.join(name)).unwrap();
        let mesh = posemfa::mesh::obj::parse_obj(name, &bytes).unwrap();
        for (j, p) in mesh.positions.iter().enumerate() {
            let u: Vec<f64> = (0..3).map(|d| (p[d] - offset[d]) * scale).collect();
            let k = labels[j].as_u64().unwrap() as usize;
            let r: Vec<f64> =
                parts[k]["rotations"][i].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
            let b: Vec<f64> =
                parts[k]["translations"][i].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
            let v: Vec<f64> = latent[j].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
            for d in 0..3 {
                let q = r[3 * d] * v[0] + r[3 * d + 1] * v[1] + r[3 * d + 2] * v[2] + b[d];
                s += (u[d] - q) * (u[d] - q);
            }
            count += 1;
        }
    }
    assert_eq!(count, pop.n_shapes() * pop.n_vertices(), "every vertex of every shape was read back");
    let recomputed = (s / count as f64).sqrt();
    assert!((recomputed - rmse).abs() <= 1e-9, "recomputed {recomputed} vs reported {rmse}");
}

#[test]
fn horse_part_count_is_stable_over_seeds_0_to_4() {
    let Some((_, pop)) = horse("horse_part_count_is_stable_over_seeds_0_to_4") else { return };
    let counts: Vec<usize> = (0..5)
        .map(|seed| fit(&pop, &Params { seed, ..Params::default() }, &mut |_| true).unwrap().model.n_parts())
        .collect();
    // a steady count: within +-2 over the seeds, i.e. all in one window of 5 counts (20..=34 at defaults)
    let (lo, hi) = (*counts.iter().min().unwrap(), *counts.iter().max().unwrap());
    assert!(hi - lo <= 4, "part counts over seeds 0-4: {counts:?}");
    assert!(lo >= 20 && hi <= 34, "part counts over seeds 0-4: {counts:?}");
}
