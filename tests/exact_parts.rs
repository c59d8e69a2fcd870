//! An exact part count (`--bones N`, `Params::target_parts`: a rig of N bones): Algorithm 1 then splits or merges
//! until it has exactly N parts, every one a connected piece of the mesh; N that cannot be met is a clear
//! error. Natively and in wasm.

#[macro_use]
mod common;

use posemfa::error::Error;
use posemfa::mfa::Params;
use posemfa::parts::hierarchy::{fit, Pipeline};
use posemfa::parts::islands::island_count;
use posemfa::synth::generate;
use posemfa::synth::presets::example;

fn distinct(labels: &[u32]) -> usize {
    let mut v = labels.to_vec();
    v.sort_unstable();
    v.dedup();
    v.len()
}

dual_test! {
    fn quadruped_and_snake_end_with_exactly_n_connected_parts() {
        for id in ["quadruped", "snake"] {
            let ex = example(id).unwrap();
            let g = generate(&ex.spec).unwrap();
            let pop = &g.population;
            let auto = fit(pop, &ex.params, &mut |_| true).unwrap().model.n_parts();
            for n in [5usize, 12, 25] {
                let params = Params { target_parts: Some(n), ..ex.params.clone() };
                let r = fit(pop, &params, &mut |_| true).unwrap();
                let m = &r.model;
                assert_eq!(m.n_parts(), n, "{id}: asked {n} (auto {auto})");
                assert_eq!(distinct(&m.labels), n, "{id}: every one of the {n} parts has vertices");
                assert_eq!(island_count(&m.labels, &pop.faces), 0, "{id} at {n}: islands");
                assert!(r.complete);
                // the log-likelihood of the refit is finite and the count cost something when far from auto
                assert!(m.log_likelihood.last().unwrap().is_finite());
                if n != auto {
                    assert!(r.stats.iter().any(|s| s.name == "parts"), "{id} at {n}: a 'parts' stage");
                }
            }
        }
    }

    fn the_count_auto_found_is_kept_as_it_is() {
        let ex = example("arm").unwrap();
        let g = generate(&ex.spec).unwrap();
        let auto = fit(&g.population, &ex.params, &mut |_| true).unwrap();
        let params = Params { target_parts: Some(auto.model.n_parts()), ..ex.params.clone() };
        let same = fit(&g.population, &params, &mut |_| true).unwrap();
        assert_eq!(same.model.labels, auto.model.labels);
        assert!(same.stats.iter().all(|s| s.name != "parts"));
    }

    fn impossible_counts_are_errors_that_say_what_to_ask() {
        let ex = example("arm").unwrap();
        let g = generate(&ex.spec).unwrap();
        let nv = g.population.n_vertices();
        for (n, want) in [(0usize, "positive whole number"), (nv + 1, "at most"), (nv / 4 + 1, "at most")] {
            let params = Params { target_parts: Some(n), ..ex.params.clone() };
            match Pipeline::new(&g.population, &params) {
                Err(Error::Params(m)) => assert!(m.contains("target_parts") && m.contains(want), "{n}: {m}"),
                Err(e) => panic!("{n}: wrong error {e:?}"),
                Ok(_) => panic!("{n} parts of {nv} vertices accepted"),
            }
        }
    }

    fn target_parts_is_target_parts_in_camel_case() {
        let p: Params = serde_json::from_str(r#"{"targetParts": 7}"#).unwrap();
        assert_eq!(p.target_parts, Some(7));
        let p: Params = serde_json::from_str(r#"{"targetParts": null}"#).unwrap();
        assert_eq!(p.target_parts, None);
        assert_eq!(serde_json::to_value(Params::default()).unwrap()["targetParts"], serde_json::Value::Null);
    }
}
