//! What crosses the wasm boundary (src/wasm.rs) as plain objects: parameters, generator specs, interpolation
//! options and shown-mesh descriptors refuse unknown fields with an error naming the field; what goes out is
//! camelCase (the articulation report, the ground-truth accuracy); errors become problems with kind, file and
//! line. The page's side of the same boundary is tested in tests/e2e/boundary.test.mjs.

#[macro_use]
mod common;

use posemfa::articulate::Options;
use posemfa::export::shown::Shown;
use posemfa::mfa::Params;
use posemfa::synth::Spec;

fn unknown_field<T: serde::de::DeserializeOwned + std::fmt::Debug>(json: &str, field: &str) {
    let e = serde_json::from_str::<T>(json).expect_err(json).to_string();
    assert!(e.contains(&format!("unknown field `{field}`")), "{json}: {e}");
}

fn keys(v: &serde_json::Value, out: &mut Vec<String>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                out.push(k.clone());
                keys(x, out);
            }
        }
        serde_json::Value::Array(a) => a.iter().for_each(|x| keys(x, out)),
        _ => {}
    }
}

dual_test! {
    fn misspelled_fields_are_errors_naming_them() {
        unknown_field::<Params>(r#"{"parts": 4, "partz": 3}"#, "partz");
        unknown_field::<Spec>(r#"{"preset": "arm", "vertexes": 500}"#, "vertexes");
        unknown_field::<Options>(r#"{"skinn": "smooth"}"#, "skinn");
        unknown_field::<Shown>(r#"{"kind": "pose", "pose": 1, "poze": 2}"#, "poze");
        // every field the page sends is known, and missing ones take their defaults
        let p: Params = serde_json::from_str(&serde_json::to_string(&Params::default()).unwrap()).unwrap();
        assert_eq!(p, Params::default());
        let o: Options = serde_json::from_str(r#"{"skin": "smooth", "residual": false}"#).unwrap();
        assert!(!o.residual);
    }

    fn reports_and_accuracy_are_camel_case() {
        let spec = Spec { preset: posemfa::synth::Preset::Arm, vertices: 800, poses: 5, ..Default::default() };
        let g = posemfa::synth::generate(&spec).unwrap();
        let params = Params { algorithm1: posemfa::mfa::Algorithm1Params { parts: 3, ..Default::default() }, ..Default::default() };
        let result = posemfa::parts::hierarchy::fit(&g.population, &params, &mut |_| true).unwrap();
        let art = posemfa::articulate::Articulation::new(&result.model, &g.population).unwrap();
        let report = posemfa::articulate::report::report(&art, 0, 3, 0.5).unwrap();
        let accuracy = posemfa::metrics::ground_truth_accuracy(&result.model, &g).unwrap();
        for v in [serde_json::to_value(&report).unwrap(), serde_json::to_value(&accuracy).unwrap()] {
            let mut k = Vec::new();
            keys(&v, &mut k);
            assert!(!k.is_empty());
            let snake: Vec<&String> = k.iter().filter(|k| k.contains('_')).collect();
            assert!(snake.is_empty(), "snake_case keys: {snake:?}");
        }
        assert_eq!(accuracy.true_parts, 3);
        // the latent shape placed for showing: every vertex moved by its part's translation in that pose
        let m = &result.model;
        let placed = m.latent_placed(2);
        for (v, p) in placed.iter().enumerate() {
            let b = m.parts[m.labels[v] as usize].translations[2];
            assert!((0..3).all(|d| (p[d] - (m.latent[v][d] + b[d])).abs() < 1e-12), "vertex {v}");
        }
        assert!(accuracy.ari > 0.5, "{accuracy:?}");
    }

    fn fit_progress_and_stages_are_camel_case() {
        // The teaching mode reads every stage the pipeline passes through, the refinement's `subParts` included
        // (it crossed as `sub_parts` and the page showed "m_k = undefined").
        let spec = Spec { preset: posemfa::synth::Preset::Arm, vertices: 800, poses: 5, ..Default::default() };
        let g = posemfa::synth::generate(&spec).unwrap();
        // Algorithm 1 (the refinement stage is its own)
        let params = Params { algorithm1: posemfa::mfa::Algorithm1Params { parts: 3, ..Default::default() }, part_rule: posemfa::mfa::PartRule::Distinct, ..Default::default() };
        let mut pipe = posemfa::parts::hierarchy::Pipeline::new(&g.population, &params).unwrap();
        let mut values = vec![serde_json::to_value(pipe.stage()).unwrap()];
        while !pipe.is_done() {
            values.push(serde_json::to_value(pipe.step().unwrap()).unwrap());
            values.push(serde_json::to_value(pipe.stage()).unwrap());
        }
        let refine: Vec<&serde_json::Value> = values.iter().filter(|v| v["kind"] == "refine").collect();
        assert!(!refine.is_empty(), "the fit never reached the refinement");
        assert!(refine.iter().all(|v| v["subParts"].as_u64().is_some_and(|m| m >= 1)), "{:?}", refine[0]);
        let mut k = Vec::new();
        for v in &values {
            keys(v, &mut k);
        }
        let snake: Vec<&String> = k.iter().filter(|k| k.contains('_')).collect();
        assert!(snake.is_empty(), "snake_case keys: {snake:?}");
    }

    fn errors_become_problems_with_file_and_line() {
        let files = vec![
            ("a.obj".to_string(), b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec()),
            ("b.obj".to_string(), b"v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n".to_vec()),
        ];
        let errors = posemfa::mesh::Population::read(posemfa::mesh::Sources::Files(files), &Default::default()).expect_err("b.obj is broken");
        let p = errors[0].problem();
        assert_eq!((p.kind, p.file.as_deref(), p.line), ("obj", Some("b.obj"), Some(2)));
        assert!(!p.message.contains("b.obj"), "{}", p.message);
    }
}
