//! The driver's unit tests: whole fits of small generated populations.

use super::tree_rule::{dissolve_start_flesh, tree_start};
use super::*;
use crate::metrics::adjusted_rand_index;
use crate::mfa::TreeParams;
use crate::synth::{generate, part_index, Preset, Spec};

#[test]
fn the_start_loses_a_band_slice_and_keeps_the_limbs() {
    // the arm with a wide blend band at the elbow, the band a start part of its own (label 3)
    let g =
        generate(&Spec { preset: Preset::Arm, vertices: 1500, poses: 8, joint_band: 0.10, ..Spec::default() }).unwrap();
    let pop = &g.population;
    let idx = |name| part_index(Preset::Arm, name).unwrap() as u32;
    let (upper, forearm) = (idx("upper_arm"), idx("forearm"));
    let mut sliced = g.part_of_vertex.clone();
    for (j, b) in g.blend.iter().enumerate() {
        if b.parts.contains(&upper) && b.parts.contains(&forearm) && b.weight > 0.02 && b.weight < 0.98 {
            sliced[j] = 3;
        }
    }
    assert!(sliced.iter().filter(|&&l| l == 3).count() >= 20);
    let data = Data::from_population(pop);
    // (the floor as given: the reference radius scales it by 1)
    let params = Params::default().for_radius(crate::mfa::params::REFERENCE_SQUARED_RADIUS);
    let start = dissolve_start_flesh(pop, &data, &sliced, &params);
    assert_eq!(start.iter().max(), Some(&2), "the slice went to its sides");
    // (a wide band's middle is about as near one side's motion as the other's)
    let (before, after) =
        (adjusted_rand_index(&sliced, &g.part_of_vertex), adjusted_rand_index(&start, &g.part_of_vertex));
    assert!(after > 0.9 && after > before, "adjusted Rand against the truth {before} -> {after}");
    // the three true parts are no blend of each other: all stay
    let kept = dissolve_start_flesh(pop, &data, &g.part_of_vertex, &params);
    assert_eq!(adjusted_rand_index(&kept, &g.part_of_vertex), 1.0);
}

#[test]
fn the_start_over_segments_a_generated_creature_inside_its_parts() {
    let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 10, ..Spec::default() }).unwrap();
    let pop = &g.population;
    let (cut, start) = tree_start(
        pop,
        &Data::from_population(pop),
        &Params::default().for_radius(crate::mfa::params::REFERENCE_SQUARED_RADIUS),
    )
    .unwrap();
    let count = |l: &[u32]| l.iter().map(|&x| x as usize + 1).max().unwrap_or(0);
    let truth = count(&g.part_of_vertex);
    assert!(
        count(&start) >= truth && count(&cut) >= count(&start),
        "cut {}, start {}, truth {truth}",
        count(&cut),
        count(&start)
    );
    // every start part lies inside one true part (the joints are where the tree stops)
    let mut inside = 0;
    for k in 0..count(&start) as u32 {
        let mut per_part = vec![0usize; truth];
        for (j, _) in start.iter().enumerate().filter(|(_, &l)| l == k) {
            per_part[g.part_of_vertex[j] as usize] += 1;
        }
        inside += per_part.iter().max().copied().unwrap_or(0);
    }
    let purity = inside as f64 / pop.n_vertices() as f64;
    assert!(purity > 0.97, "purity {purity}");
}

#[test]
fn parts_the_rule_leaves_alone_go_on_from_the_loose_run() {
    // a generated quadruped: the part rule's opening round keeps the first run's parts as they are
    let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 10, ..Spec::default() }).unwrap();
    let mut pipe = Pipeline::new(&g.population, &Params::default()).unwrap();
    let mut runs: Vec<Vec<f64>> = vec![Vec::new()];
    while !pipe.is_done() {
        let p = pipe.step().unwrap();
        runs.last_mut().unwrap().push(p.log_likelihood);
        if p.run_finished && !pipe.is_done() {
            runs.push(Vec::new());
        }
    }
    let names: Vec<&str> = pipe.stats.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["tree", "final", "final"], "the opening round removed nothing");
    // the second run starts where the first stopped (its components), so AECM's monotonicity carries over
    // from one run to the next; a start again from labels begins below it
    let (first, second) = (&runs[0], &runs[1]);
    let last = *first.last().unwrap();
    assert!(
        second[0] >= last - 1e-9 * last.abs(),
        "second run starts at {} after the first ended at {last}",
        second[0]
    );
    assert!(second.len() < first.len(), "{} iterations after {}", second.len(), first.len());
    let result = pipe.result();
    assert_eq!(result.model.n_parts(), 18);
}

#[test]
fn a_refit_after_a_merge_goes_on_from_the_parts_that_stayed() {
    let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 10, ..Spec::default() }).unwrap();
    let mut pipe = Pipeline::new(&g.population, &Params::default()).unwrap();
    let done = pipe.run(&mut |_| true).unwrap();
    let last = pipe.last_run.clone().expect("the last run's model is kept");
    // the cheapest merge of the fitted parts' tree (the merge the part rule's rule 2 would make next)
    let tree = done.merge_tree().expect("the tree pipeline keeps its tree");
    let merged = tree.labels_at(done.model.n_parts() - 1);
    let mut cold = Pipeline::new(&g.population, &Params::default()).unwrap();
    let state = cold.refit(FinalRun::Round, &merged).unwrap();
    let State::Final(mut cold) = state else { panic!("a refit is a final-stage run") };
    let State::Final(mut warm) = pipe.refit_warm(FinalRun::Round, &merged).unwrap() else {
        panic!("a refit is a final-stage run")
    };
    // every part that is one of the last run's (all but at most the union) starts from that run's component
    let before = crate::mfa::data::to_frame(warm.data(), &last.parts);
    let same = super::super::labels::same_parts(&merged, &last.labels);
    assert!(same.iter().filter(|s| s.is_some()).count() + 1 >= same.len(), "{same:?}");
    for (c, s) in warm.components().iter().zip(&same) {
        if let Some(b) = s {
            assert_eq!(c.rotations, before[*b as usize].rotations);
            assert_eq!(c.translations, before[*b as usize].translations);
        }
    }
    // and it ends where the refit from labels ends
    while !warm.is_finished() {
        warm.step();
    }
    while !cold.is_finished() {
        cold.step();
    }
    let (w, c) = (warm.model(), cold.model());
    assert_eq!(w.n_parts(), c.n_parts());
    assert!(adjusted_rand_index(&w.labels, &c.labels) > 0.99);
}

#[test]
fn a_refine_from_the_merge_trees_partition_keeps_that_partition() {
    // the page's "Refine N parts": the fitted parts' tree cut at N, then the fit from those labels; on all
    // vertices and on a coarse mesh (each coarse vertex takes its seed's part)
    let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 20, ..Spec::default() }).unwrap();
    for coarse_vertices in [0, 1000] {
        let base = Params { tree: TreeParams { coarse_vertices }, ..Params::default() };
        let auto = fit(&g.population, &base, &mut |_| true).unwrap();
        let n = auto.model.n_parts() - 4;
        let start = auto.merge_tree().expect("the tree rule's tree").labels_at(n);
        let refined = fit_from(&g.population, &base, &FitStart { labels: Some(start.clone()) }, &mut |_| true).unwrap();
        assert_eq!(refined.model.n_parts(), n, "coarse {coarse_vertices}");
        // every part is one of the partition shown: more than half of each in the other
        let (a, b) = (&refined.model.labels, &start);
        let mut overlap = std::collections::HashMap::new();
        let (mut size_a, mut size_b) = (vec![0usize; n], vec![0usize; n]);
        for (&x, &y) in a.iter().zip(b) {
            *overlap.entry((x, y)).or_insert(0usize) += 1;
            size_a[x as usize] += 1;
            size_b[y as usize] += 1;
        }
        let same =
            overlap.iter().filter(|(&(x, y), &k)| 2 * k > size_a[x as usize] && 2 * k > size_b[y as usize]).count();
        assert_eq!(same, n, "coarse {coarse_vertices}: {same} of the {n} parts shown came out of the refit");
        let ari = adjusted_rand_index(a, b);
        assert!(ari > 0.9, "coarse {coarse_vertices}: the refit moved away from the partition shown ({ari:.3})");
    }
    // what is not a start is refused, naming the field
    let short = FitStart { labels: Some(vec![0; 10]) };
    let e = Pipeline::starting(&g.population, &Params::default(), &short).err().expect("refused").to_string();
    assert!(e.contains("startLabels has 10 labels for a population of"), "{e}");
    let distinct = Params { part_rule: PartRule::Distinct, ..Params::default() };
    let all_one = FitStart { labels: Some(vec![0; g.population.n_vertices()]) };
    let e = Pipeline::starting(&g.population, &distinct, &all_one).err().expect("refused").to_string();
    assert!(e.contains("startLabels needs the merge tree's part rule"), "{e}");
}

#[test]
fn an_exact_count_is_made_on_the_coarse_mesh() {
    let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 20, ..Spec::default() }).unwrap();
    let params = Params { tree: TreeParams { coarse_vertices: 1000 }, target_parts: Some(12), ..Params::default() };
    let result = fit(&g.population, &params, &mut |_| true).unwrap();
    assert_eq!(result.model.n_parts(), 12);
    let names: Vec<&str> = result.stats.iter().map(|s| s.name.as_str()).collect();
    let (parts, all) = (names.iter().position(|&n| n == "parts"), names.iter().position(|&n| n == "all vertices"));
    assert!(parts.is_some() && parts < all, "the count on the coarse mesh, then all vertices: {names:?}");
    // a count the coarse mesh cannot hold (4 vertices a part) is made on all vertices
    let many = Params { tree: TreeParams { coarse_vertices: 1000 }, target_parts: Some(300), ..Params::default() };
    assert!(!Pipeline::new(&g.population, &many).unwrap().on_coarse_mesh());
}

#[test]
fn fewer_poses_get_a_larger_coarse_mesh() {
    // 10 poses of 24 000 vertices: a coarse mesh of 16 000 would be more than half of them, so all vertices
    let g = generate(&Spec { preset: Preset::Arm, vertices: 24000, poses: 10, ..Spec::default() }).unwrap();
    assert!(!Pipeline::new(&g.population, &Params::default()).unwrap().on_coarse_mesh());
    assert_eq!(coarse_target(8000, 10), 16000);
    assert_eq!(coarse_target(8000, 11), 14545);
    assert_eq!((coarse_target(8000, 20), coarse_target(8000, 200)), (8000, 8000));
    // 24 000 vertices in 20 poses: the default 8 000
    let g = generate(&Spec { preset: Preset::Arm, vertices: 24000, poses: 20, ..Spec::default() }).unwrap();
    let pipe = Pipeline::new(&g.population, &Params::default()).unwrap();
    assert!(pipe.on_coarse_mesh());
    assert_eq!(pipe.current_vertices().map(|v| v.len()), Some(8000));
}

#[test]
fn a_population_is_judged_on_all_its_vertices_not_the_coarse_mesh() {
    // only 30 vertices that are no seed of the coarse mesh move: the population moves
    let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 20, ..Spec::default() }).unwrap();
    let mut pop = g.population.clone();
    let seeds = super::super::coarse_mesh::CoarseMesh::build(&pop, 1000).seeds;
    let mut shapes = vec![pop.shape(0).to_vec(); pop.n_shapes()];
    let movers: Vec<usize> = (0..pop.n_vertices()).filter(|j| !seeds.contains(j)).take(30).collect();
    for (i, s) in shapes.iter_mut().enumerate() {
        for &j in &movers {
            s[j][2] += 0.01 * i as f64;
        }
    }
    pop.set_shapes(&shapes);
    let params = Params { tree: TreeParams { coarse_vertices: 1000 }, ..Params::default() };
    let pipe = Pipeline::new(&pop, &params).expect("the population moves");
    assert!(pipe.on_coarse_mesh());
}

#[test]
fn parts_decided_on_a_coarse_mesh_are_the_parts_of_all_vertices() {
    // 3 000 vertices, decided on a coarse mesh of 1 000 (at least COARSE_FACTOR times as many; 20 poses:
    // with fewer the coarse mesh is larger)
    let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 20, ..Spec::default() }).unwrap();
    let pop = &g.population;
    let nv = pop.n_vertices();
    let params = Params { tree: TreeParams { coarse_vertices: 1000 }, ..Params::default() };
    let mut pipe = Pipeline::new(pop, &params).unwrap();
    assert!(pipe.on_coarse_mesh());
    assert_eq!(pipe.population().n_vertices(), nv);
    assert_eq!(pipe.current_vertices().map(|v| v.len()), Some(1000), "the first run is on the coarse mesh");
    assert_eq!(pipe.current_labels().len(), nv);
    // a fit stopped while deciding gives a model of every vertex
    pipe.step().unwrap();
    let early = pipe.result();
    assert_eq!((early.model.labels.len(), early.model.latent.len()), (nv, nv));
    // every run, on the coarse mesh and on all vertices, is an AECM run: its log-likelihood never falls
    // (but where a component is dropped)
    let mut last: Option<(f64, usize)> = None;
    while !pipe.is_done() {
        let p = pipe.step().unwrap();
        if let Some((ll, parts)) = last.filter(|&(_, parts)| parts == p.parts) {
            assert!(
                p.log_likelihood >= ll - 1e-9 * ll.abs(),
                "{:?}: {} after {ll} ({parts} parts)",
                p.stage,
                p.log_likelihood
            );
        }
        last = (!p.run_finished).then_some((p.log_likelihood, p.parts));
    }
    let result = pipe.result();
    assert!(!pipe.on_coarse_mesh());
    let names: Vec<&str> = result.stats.iter().map(|s| s.name.as_str()).collect();
    assert_eq!((names[0], *names.last().unwrap()), ("tree", "all vertices"), "{names:?}");
    // everything per vertex is per vertex of the population
    assert_eq!(result.model.n_vertices, nv);
    let tree = result.merge_tree().expect("the merge tree is kept");
    assert_eq!(tree.leaves.len(), nv);
    assert_eq!((result.coarse_labels.len(), result.refined_labels.len()), (nv, nv));
    // the parts: the creature's, as the decisions on all vertices find them
    let all =
        fit(pop, &Params { tree: TreeParams { coarse_vertices: 0 }, ..Params::default() }, &mut |_| true).unwrap();
    assert_eq!(result.model.n_parts(), all.model.n_parts());
    let truth = adjusted_rand_index(&result.model.labels, &g.part_of_vertex);
    let same = adjusted_rand_index(&result.model.labels, &all.model.labels);
    assert!(
        truth > 0.95 && same > 0.95,
        "adjusted Rand against the truth {truth}, against the fit on all vertices {same}"
    );
    // and the fit of all vertices is converged at the fit's tolerance, as good as the one decided there
    assert!(result.model.converged);
    let (rmse, rmse_all) = (result.model.rmse(pop), all.model.rmse(pop));
    assert!(rmse < 1.05 * rmse_all, "RMSE {rmse} against {rmse_all}");
}

/// Which rule a fit follows is said once ([`rule_of`]): the merge tree only with its part rule and the
/// refinement on; the refinement off is Algorithm 1's coarse stage alone, which the trace says and the result
/// reports (the run's stage and the rule's report), as does each final-stage run it makes.
#[test]
fn the_rule_is_chosen_in_one_place_and_the_refinement_off_says_so() {
    let tree = Params::default();
    let coarse_only = Params { refine: false, ..Params::default() };
    let distinct = Params { part_rule: PartRule::Distinct, ..Params::default() };
    assert_eq!(
        (rule_of(&tree), rule_of(&coarse_only), rule_of(&distinct)),
        (Rule::MergeTree, Rule::Algorithm1, Rule::Algorithm1)
    );
    let g = generate(&Spec { preset: Preset::Arm, vertices: 400, poses: 5, ..Spec::default() }).unwrap();
    let lines = std::rc::Rc::new(std::cell::RefCell::new(Vec::<String>::new()));
    let kept = lines.clone();
    crate::trace::set_sink(Some(Box::new(move |l: &str| kept.borrow_mut().push(l.to_string()))));
    let pipe = Pipeline::new(&g.population, &coarse_only);
    crate::trace::set_sink(None);
    let mut pipe = pipe.unwrap();
    assert!(
        lines.borrow().iter().any(|l| l.starts_with("refinement off: Algorithm 1's coarse stage alone")),
        "{lines:?}"
    );
    assert_eq!((pipe.rule(), pipe.stage()), (Rule::Algorithm1, Stage::Coarse));
    let result = pipe.run(&mut |_| true).unwrap();
    assert_eq!(result.rule, RuleReport::Algorithm1 { refined: false });
    assert!(!result.from_merge_tree() && !result.refined() && result.merge_tree().is_none());
    // the default: the merge tree's first run, and its report
    let pipe = Pipeline::new(&g.population, &tree).unwrap();
    assert!(matches!(pipe.stage(), Stage::Final { rule: Rule::MergeTree, run: FinalRun::First, number: 1, .. }));
    let result = fit(&g.population, &tree, &mut |_| true).unwrap();
    assert!(result.from_merge_tree() && result.refined() && result.merge_tree().is_some());
    assert!(result.tree_count().is_some());
    assert_eq!(result.tree_count(), result.tree_cuts().and_then(|c| c.decided()));
}
