// local probe (not committed): PRESETS VERTICES POSES SEEDS ; params JSON in POSEMFA_PARAMS
use posemfa::model::hierarchy::fit;
use posemfa::model::Params;
use posemfa::synth;
fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let list = |s: &str| s.split(',').map(|x| x.to_string()).collect::<Vec<_>>();
    let base: Params = std::env::var("POSEMFA_PARAMS").ok().map(|s| serde_json::from_str(&s).unwrap()).unwrap_or_default();
    for p in list(&a[0]) {
        if p.starts_with('/') {
            let pop = posemfa::mesh::Population::from_paths_with(&[p.clone()], &Default::default()).unwrap();
            for s in list(&a[3]) {
                let params = Params { seed: s.parse().unwrap(), ..base.clone() };
                let t = std::time::Instant::now();
                let r = fit(&pop, &params, &mut |_| true).unwrap();
                println!("{p} s={s} parts={} rmse={:.5} t={:.1}s", r.model.n_parts(), r.model.rmse(&pop), t.elapsed().as_secs_f64());
            }
            continue;
        }
        for v in list(&a[1]) {
            for n in list(&a[2]) {
                for s in list(&a[3]) {
                    let preset = serde_json::from_value(serde_json::json!(p)).unwrap();
                    let spec = synth::Spec { preset, vertices: v.parse().unwrap(), poses: n.parse().unwrap(), seed: s.parse().unwrap(), ..Default::default() };
                    let g = synth::generate(&spec).unwrap();
                    if std::env::var_os("TRUTH").is_some() {
                        let d = posemfa::model::data::Data::from_population(&g.population);
                        let names = synth::part_names(preset);
                        let parents = synth::part_parents(preset);
                        let mem = |k: usize| (0..g.part_of_vertex.len()).filter(|&j| g.part_of_vertex[j] as usize == k).collect::<Vec<_>>();
                        for k in 0..g.n_parts() {
                            let m = mem(k);
                            let c = posemfa::model::init::component_from_points(&d, &m, m.len(), 1e-7);
                            let mut line = format!("  {:20} n={:5} rel={:.2e} abs={:.2e}", names[k], m.len(), c.mean_variance(), c.mean_variance());
                            if let Some(pa) = parents[k] {
                                let mut u = m.clone(); u.extend(mem(pa));
                                let cu = posemfa::model::init::component_from_points(&d, &u, u.len(), 1e-7);
                                line += &format!("  +parent {:16} rel={:.2e} abs={:.2e}", names[pa], cu.mean_variance(), cu.mean_variance());
                            }
                            println!("{line}");
                        }
                    }
                    let params = Params { seed: s.parse().unwrap(), ..base.clone() };
                    let t = std::time::Instant::now();
                    let r = fit(&g.population, &params, &mut |_| true).unwrap();
                    let acc = posemfa::metrics::ground_truth_accuracy(&r.model, &g).unwrap();
                    if std::env::var_os("ROTS").is_some() { println!("{:?}", acc.rotation_errors_deg.iter().map(|x| (x * 10.0).round() / 10.0).collect::<Vec<_>>()); }
                    println!("{p:10} v={v:6} n={n:3} s={s} true={:2} parts={:2} (ref {:2}) ari={:.3} rot med={:.2} max={:.2} rmse={:.5} t={:.1}s",
                        acc.true_parts, r.model.n_parts(), r.stages.refined_parts, acc.ari, acc.rotation_error_deg, acc.rotation_error_deg_max, r.model.rmse(&g.population), t.elapsed().as_secs_f64());
                }
            }
        }
    }
}
