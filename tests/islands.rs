//! Every part of a finished fit is one connected piece of the mesh (`islands` is 0: a rig bone moves one
//! piece) on every built-in generated example over seeds 0-4 and, natively, on horse-poses and horse-gallop when
//! ../shared/data is present (skipped, saying so, when absent).

#[macro_use]
mod common;

use posemfa::export::json::fit_to_json;
use posemfa::mesh::Population;
use posemfa::mfa::Params;
use posemfa::parts::hierarchy::fit;
use posemfa::parts::islands::island_count;
use posemfa::synth::generate;
use posemfa::synth::presets::examples;

fn islands_of(pop: &Population, params: &Params) -> (usize, usize) {
    let r = fit(pop, params, &mut |_| true).unwrap();
    let json: serde_json::Value = serde_json::from_str(&fit_to_json(pop, &r)).unwrap();
    let reported = json["islands"].as_u64().expect("islands in the JSON") as usize;
    // the JSON's figure is the labels' own count
    assert_eq!(reported, island_count(&r.model.labels, pop.graph_faces()));
    (reported, r.model.n_parts())
}

dual_test! {
    fn every_generated_example_has_connected_parts_over_seeds_0_to_4() {
        for ex in examples() {
            for seed in 0..5u64 {
                let mut spec = ex.spec.clone();
                spec.seed = seed;
                let g = generate(&spec).unwrap();
                let params = Params { seed, ..ex.params.clone() };
                let (islands, parts) = islands_of(&g.population, &params);
                assert_eq!(islands, 0, "example {} seed {seed}: {islands} islands ({parts} parts)", ex.id);
            }
        }
    }
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn horse_populations_have_connected_parts() {
    for name in ["horse-poses", "horse-gallop"] {
        let Some(dir) = common::shared_dir(&format!("data/{name}"), "horse_populations_have_connected_parts") else {
            return;
        };
        let pop = Population::new(posemfa::mesh::Sources::paths(&[dir])).unwrap();
        for seed in 0..2u64 {
            let (islands, parts) = islands_of(&pop, &Params { seed, ..Params::default() });
            assert_eq!(islands, 0, "{name} seed {seed}: {islands} islands ({parts} parts)");
        }
    }
}
