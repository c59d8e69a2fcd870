//! The model file (src/model_file.rs): a fit saved and opened again is the same fit, number for number, and
//! every export made from it is the same file, byte for byte; a file that is cut, damaged, of a newer version or
//! of another mesh is refused by name. On generated populations (natively and in wasm) and on the real ones of
//! ../shared/data (natively; skipped, counted as skipped, when absent).

#[macro_use]
mod common;

use posemfa::articulate::{Articulation, Options};
use posemfa::error::Error;
use posemfa::export::gltf::{to_glb, GltfOptions, Weights};
use posemfa::export::json::fit_to_json;
use posemfa::mesh::Population;
use posemfa::mfa::Params;
use posemfa::model_file::{ModelFile, MAGIC, VERSION};
use posemfa::parts::hierarchy::{fit, FitResult};
use posemfa::synth::{generate, Preset, Spec};

fn generated(preset: Preset, vertices: usize, poses: usize) -> Population {
    let spec = Spec { preset, vertices, poses, seed: 3, ..Default::default() };
    generate(&spec).expect("generates").population
}

fn fitted(pop: &Population, params: &Params) -> FitResult {
    fit(pop, params, &mut |_| true).expect("fits")
}

/// Every field of the fit the same, the f64s bit for bit (FitResult has no PartialEq: its JSON covers most, the
/// rest is compared here).
fn assert_same_fit(a: &FitResult, b: &FitResult) {
    assert_eq!(a.model, b.model, "the model (parts, labels, latent, log-likelihood)");
    assert_eq!(a.coarse_labels, b.coarse_labels);
    assert_eq!(a.refined_labels, b.refined_labels);
    assert_eq!(a.decided_labels, b.decided_labels);
    assert_eq!(a.stages, b.stages);
    assert_eq!(a.stats, b.stats);
    assert_eq!(a.complete, b.complete);
    assert_eq!(a.part_curve.len(), b.part_curve.len());
    for (x, y) in a.part_curve.iter().zip(&b.part_curve) {
        assert_eq!((x.parts, x.merged), (y.parts, y.merged));
        assert_eq!((x.score.to_bits(), x.variance.to_bits()), (y.score.to_bits(), y.variance.to_bits()));
    }
    assert_eq!(a.part_rounds, b.part_rounds);
    assert_eq!(a.start_parts(), b.start_parts());
    assert_eq!(a.merge_tree(), b.merge_tree(), "the merge tree");
    if let (Some(x), Some(y)) = (a.merge_tree(), b.merge_tree()) {
        assert_eq!(x.middle_typical().to_bits(), y.middle_typical().to_bits());
    }
    assert_eq!(a.tree_count(), b.tree_count());
    assert_eq!(a.rule, b.rule, "the rule's report");
    assert_eq!(
        (a.from_merge_tree(), a.count_unjudged, a.refined(), a.parts_asked),
        (b.from_merge_tree(), b.count_unjudged, b.refined(), b.parts_asked)
    );
}

/// The exports of a fit: the JSON, the rig with rigid and fitted weights, and an interpolated pose as OBJ.
fn exports(pop: &Population, result: &FitResult) -> Vec<Vec<u8>> {
    let art = Articulation::new(&result.model, pop).expect("articulates");
    let rigid = to_glb(&art, &GltfOptions::default()).expect("rigid rig");
    let fitted = to_glb(&art, &GltfOptions { weights: Weights::Fitted, ..Default::default() }).expect("fitted rig");
    let pose = art.interpolate(0, pop.n_shapes() - 1, 0.4, &Options::default()).expect("interpolates");
    let obj = posemfa::export::obj::write_obj(&art.to_original(&pose), &pop.faces, "t = 0.4");
    vec![fit_to_json(pop, result).into_bytes(), rigid, fitted, obj.into_bytes()]
}

/// Bytes a vertex of a model file saved without its poses, less what the parts and poses take (the parts' f64
/// parameters in every pose, and the header: the poses' names, the statistics).
fn bytes_per_vertex(file: &[u8], result: &FitResult) -> f64 {
    let m = &result.model;
    let header = u32::from_le_bytes(file[12..16].try_into().unwrap()) as usize;
    let parts = m.n_parts() * (m.n_shapes * 13 + 4) * 8;
    (file.len() - 24 - header - parts) as f64 / m.n_vertices as f64
}

/// Saves, opens, and checks the fit, the population and every export; then the same without the poses, and
/// with the poses given back. Returns the two files' sizes.
fn round_trip(name: &str, pop: &Population, params: &Params) -> (usize, usize) {
    let result = fitted(pop, params);
    let saved = ModelFile::new(pop.clone(), result, params.clone());
    let bytes = saved.to_bytes(true);
    let opened = ModelFile::from_bytes(name, &bytes).expect("opens");
    assert!(opened.has_data);
    assert_eq!(&opened.population, pop, "{name}: the population");
    assert_eq!(opened.params, *params, "{name}: the parameters");
    assert_eq!(opened.summary, saved.summary, "{name}: the summary");
    assert_same_fit(&saved.result, &opened.result);
    let before = exports(pop, &saved.result);
    let after = exports(&opened.population, &opened.result);
    for (k, (x, y)) in before.iter().zip(&after).enumerate() {
        assert!(x == y, "{name}: export {k} (json, rigid glb, fitted glb, obj) differs after the round trip");
    }
    // saved again from what was opened: the same file
    assert!(opened.to_bytes(true) == bytes, "{name}: saving the opened model writes another file");

    // without the poses: the model the same, the poses its reconstructions, the figures those saved
    let small = saved.to_bytes(false);
    let per_vertex = bytes_per_vertex(&small, &saved.result);
    assert!(per_vertex <= 40.0, "{name}: {per_vertex:.1} bytes a vertex without the poses");
    let bare = ModelFile::from_bytes(name, &small).expect("opens without poses");
    assert!(!bare.has_data);
    assert_same_fit(&saved.result, &bare.result);
    assert_eq!(bare.summary, saved.summary);
    assert_eq!(bare.population.n_vertices(), pop.n_vertices());
    assert_eq!(bare.population.names, pop.names);
    let recon = saved.result.model.reconstruct(1);
    let stand_in = bare.population.shape(1).to_vec();
    let worst = recon.iter().zip(&stand_in).map(|(a, b)| (0..3).map(|d| (a[d] - b[d]).abs()).fold(0.0, f64::max));
    assert!(worst.fold(0.0, f64::max) < 1e-6, "{name}: the stand-in poses are the reconstructions");
    // given its poses back, it is the fit with its poses again
    let whole = bare.with_population(name, pop.clone()).expect("the same mesh");
    let again = exports(&whole.population, &whole.result);
    assert!(again == before, "{name}: exports after the poses were given back");
    (bytes.len(), small.len())
}

/// The JSON header of model file `bytes`.
fn header_text(bytes: &[u8]) -> String {
    let n = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    String::from_utf8(bytes[24..24 + n].to_vec()).unwrap()
}

/// `bytes` (a model file) with another JSON header, the body where it was.
fn with_header(bytes: &[u8], header: &str) -> Vec<u8> {
    let n = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let body = &bytes[(24 + n).div_ceil(8) * 8..];
    let mut out = bytes[..12].to_vec();
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(&bytes[16..24]);
    out.extend_from_slice(header.as_bytes());
    out.resize((24 + header.len()).div_ceil(8) * 8, 0);
    out.extend_from_slice(body);
    out
}

dual_test! {
    fn a_generated_fit_opens_as_the_same_fit_with_the_same_exports() {
        let pop = generated(Preset::Quadruped, 1500, 6);
        let (with, without) = round_trip("quadruped.posemfa", &pop, &Params::default());
        // the poses as f32 and the triangles as u32, and what the budget allows on top
        let raw = pop.n_shapes() * pop.n_vertices() * 12 + pop.faces.len() * 12;
        assert!((with as f64) <= 1.3 * raw as f64, "{with} bytes for {raw} bytes of f32 points and u32 triangles");
        assert!(without < with);
    }

    fn algorithm_1_and_an_exact_count_survive_the_round_trip() {
        let pop = generated(Preset::Arm, 800, 5);
        let distinct = Params { part_rule: posemfa::mfa::PartRule::Distinct, ..Params::default() };
        round_trip("arm-distinct.posemfa", &pop, &distinct);
        let exact = Params { target_parts: Some(3), ..Params::default() };
        round_trip("arm-3.posemfa", &pop, &exact);
    }

    fn a_cut_file_is_refused_by_name_at_every_length() {
        let pop = generated(Preset::Snake, 300, 4);
        let bytes = ModelFile::new(pop.clone(), fitted(&pop, &Params::default()), Params::default()).to_bytes(true);
        let step = (bytes.len() / 97).max(1);
        for cut in (0..bytes.len()).step_by(step) {
            let e = ModelFile::from_bytes("cut.posemfa", &bytes[..cut]).expect_err("a cut file is refused");
            let text = e.to_string();
            assert!(text.starts_with("model file cut.posemfa: "), "{text}");
            if cut >= 24 {
                assert!(text.contains("cut short"), "cut at {cut}: {text}");
            }
        }
    }

    fn a_newer_version_an_unknown_file_and_damage_are_refused_by_name() {
        let pop = generated(Preset::Snake, 300, 4);
        let bytes = ModelFile::new(pop.clone(), fitted(&pop, &Params::default()), Params::default()).to_bytes(true);
        let mut newer = bytes.clone();
        newer[8..12].copy_from_slice(&(VERSION + 1).to_le_bytes());
        let e = ModelFile::from_bytes("new.posemfa", &newer).unwrap_err().to_string();
        assert!(e.contains(&format!("format version {}", VERSION + 1)) && e.contains("newer posemfa"), "{e}");

        let e = ModelFile::from_bytes("pose.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap_err().to_string();
        assert!(e.contains("not a posemfa model file"), "{e}");
        assert!(posemfa::model_file::looks_like(&bytes) && &bytes[..8] == MAGIC);

        // a header field of the wrong type, named with its path
        let text = header_text(&bytes);
        let damaged = with_header(&bytes, &text.replacen("\"converged\":", "\"converged\":\"yes\",\"was\":", 1));
        let e = ModelFile::from_bytes("d.posemfa", &damaged).unwrap_err().to_string();
        assert!(e.contains("header field fit.converged: invalid type: string \"yes\""), "{e}");
        let damaged = with_header(&bytes, &text.replacen("\"names\":[", "\"names\":[\"extra.obj\",", 1));
        let e = ModelFile::from_bytes("n.posemfa", &damaged).unwrap_err().to_string();
        assert!(e.contains("header field population.names: 5 names for 4 poses"), "{e}");
        let damaged = with_header(&bytes, &text.replacen("\"fit\":{", "\"fit\":{\"colour\":1,", 1));
        let e = ModelFile::from_bytes("u.posemfa", &damaged).unwrap_err().to_string();
        assert!(e.contains("header field fit.colour: unknown field `colour`"), "{e}");

        // counts far past what the body holds are refused before anything their size is made
        let nv = pop.n_vertices();
        let huge = with_header(&bytes, &text.replacen(&format!("\"vertices\":{nv},"), "\"vertices\":4000000000,", 1));
        let e = ModelFile::from_bytes("h.posemfa", &huge).unwrap_err().to_string();
        assert!(e.contains(&format!("array 'labels': {nv} elements where the header's counts call for 4000000000")), "{e}");
        let at = text.find("\"nLeaves\":").expect("the header has the merge tree");
        let end = at + 10 + text[at + 10..].find(',').unwrap();
        let leaves = format!("{}\"nLeaves\":4000000000{}", &text[..at], &text[end..]);
        let e = ModelFile::from_bytes("t.posemfa", &with_header(&bytes, &leaves)).unwrap_err().to_string();
        assert!(e.contains("header field fit.mergeTree: 4000000000 leaves"), "{e}");
        // the rule's own report: the merge tree's fields with Algorithm 1, or that rule without its refinement
        let algorithm1 = with_header(&bytes, &text.replacen("\"fromMergeTree\":true", "\"fromMergeTree\":false", 1));
        let e = ModelFile::from_bytes("r.posemfa", &algorithm1).unwrap_err().to_string();
        assert!(e.contains("header field fit.fromMergeTree: false, yet the fit has the merge tree's"), "{e}");
        let unrefined = with_header(&bytes, &text.replacen("\"refined\":true", "\"refined\":false", 1));
        let e = ModelFile::from_bytes("f.posemfa", &unrefined).unwrap_err().to_string();
        assert!(e.contains("header field fit.refined: false, yet the parts came from the merge tree"), "{e}");

        // a label past the parts, in the body
        let saved = ModelFile::from_bytes("ok.posemfa", &bytes).unwrap();
        let mut bad = saved.clone();
        bad.result.model.labels[7] = bad.result.model.n_parts() as u32 + 2;
        let e = ModelFile::from_bytes("l.posemfa", &bad.to_bytes(true)).unwrap_err().to_string();
        assert!(e.contains("array 'labels', element 7"), "{e}");
    }

    fn a_kept_rig_writes_the_rig_built_and_serves_only_that_rig() {
        use posemfa::model_file::SavedRig;
        let pop = generated(Preset::Quadruped, 1200, 5);
        let result = fitted(&pop, &Params::default());
        let mut file = ModelFile::new(pop.clone(), result.clone(), Params::default());
        // without a rig the file is version 1, as before
        assert_eq!(&file.to_bytes(true)[8..12], &1u32.to_le_bytes());
        let g = GltfOptions { weights: Weights::Fitted, ..GltfOptions::default() };
        let band = posemfa::articulate::skin::DEFAULT_BAND;
        file.rig = Some(SavedRig::build(&result.model, &pop, band, g.rig_options()).unwrap());
        let bytes = file.to_bytes(true);
        assert_eq!(&bytes[8..12], &2u32.to_le_bytes(), "a file with a rig is version 2");
        let read = ModelFile::from_bytes("rig.posemfa", &bytes).unwrap();
        let saved = read.rig.as_ref().expect("the rig is read back");
        // the kept rig writes the very .glb that building it writes
        let art = Articulation::with_band(&read.result.model, &read.population, band).unwrap();
        let kept = saved.for_request(&read.population, band, &g.rig_options()).expect("the rig asked for");
        let glb = posemfa::export::gltf::write_glb(&art, kept, &g).unwrap();
        assert!(glb == to_glb(&art, &g).unwrap(), "the kept rig's .glb is the built rig's, byte for byte");
        // what the page's Rig panel, Python's rig_glb and pose mode call: the kept rig when it is the one asked for
        use posemfa::export::rig_report::export_rig;
        use posemfa::model_file::RigSource;
        let from_file = export_rig(&art, &read.population, &g, Some(saved)).unwrap();
        let built = export_rig(&art, &read.population, &g, None).unwrap();
        assert_eq!((from_file.source, built.source), (RigSource::ModelFile, RigSource::Built));
        assert!(from_file.glb == built.glb && from_file.error.e_rms == built.error.e_rms);
        let three_built = export_rig(&art, &read.population, &GltfOptions { influences: 3, ..g }, Some(saved)).unwrap();
        assert_eq!(three_built.source, RigSource::Built, "other options build their own rig");
        let poser = |kept| posemfa::export::pose_glb::Poser::new(&art, &read.population, &g, kept).unwrap();
        let (a, b) = (poser(Some(saved)), poser(None));
        assert!(a.bone_of_vertex == b.bone_of_vertex && a.diagonal == b.diagonal);
        // other options, another band or other poses: not that rig
        let three = GltfOptions { influences: 3, ..g };
        assert!(saved.for_request(&read.population, band, &three.rig_options()).is_none());
        assert!(saved.for_request(&read.population, band * 2.0, &g.rig_options()).is_none());
        let mut points: Vec<[f32; 3]> = (0..pop.n_shapes()).flat_map(|i| pop.shape(i).as_f32().to_vec()).collect();
        let same = Population::new(posemfa::mesh::Sources::Saved(posemfa::mesh::Saved { file: "same".into(), names: pop.names.clone(), faces: pop.faces.to_vec(), points: points.clone(), normalization: pop.normalization, source: pop.source.clone() })).unwrap();
        assert!(saved.for_request(&same, band, &g.rig_options()).is_some(), "the same poses read again");
        points[5][0] += 1e-3;
        let moved = Population::new(posemfa::mesh::Sources::Saved(posemfa::mesh::Saved { file: "moved".into(), names: pop.names.clone(), faces: pop.faces.to_vec(), points, normalization: pop.normalization, source: pop.source.clone() })).unwrap();
        assert!(saved.for_request(&moved, band, &g.rig_options()).is_none(), "one point moved: other poses");

        // damage in the rig's header is refused by name
        let text = header_text(&bytes);
        let influences = saved.rig.weights.influences.iter().map(Vec::len).sum::<usize>();
        let damaged = text.replacen(&format!("\"influences\":{influences}"), &format!("\"influences\":{}", influences + 1), 1);
        let e = ModelFile::from_bytes("r.posemfa", &with_header(&bytes, &damaged)).unwrap_err().to_string();
        assert!(e.contains("rigBones") || e.contains("rig.influences"), "{e}");
        let at = text.find("\"order\":[").unwrap() + 9;
        let first = &text[at..at + text[at..].find([',', ']']).unwrap()];
        let damaged = format!("{}{first},{}", &text[..at], &text[at..]);
        let e = ModelFile::from_bytes("o.posemfa", &with_header(&bytes, &damaged)).unwrap_err().to_string();
        assert!(e.contains("header field rig.order: entry 1"), "{e}");
        // a version 1 file has no rig
        let mut v1 = with_header(&bytes, &text.replacen("\"version\":2", "\"version\":1", 1));
        v1[8..12].copy_from_slice(&1u32.to_le_bytes());
        let e = ModelFile::from_bytes("v1.posemfa", &v1).unwrap_err().to_string();
        assert!(e.contains("a version 1 file has no rig"), "{e}");
    }

    fn poses_of_another_mesh_are_refused_by_name() {
        let pop = generated(Preset::Snake, 300, 4);
        let bytes = ModelFile::new(pop.clone(), fitted(&pop, &Params::default()), Params::default()).to_bytes(false);
        let bare = ModelFile::from_bytes("snake.posemfa", &bytes).unwrap();
        let other = generated(Preset::Arm, 800, 4);
        let e = bare.clone().with_population("snake.posemfa", other).unwrap_err();
        assert!(matches!(e, Error::ModelFile { .. }));
        assert!(e.to_string().contains("fitted to another mesh") && e.to_string().contains("vertices"), "{e}");
        let fewer = generated(Preset::Snake, 300, 3);
        let e = bare.with_population("snake.posemfa", fewer).unwrap_err().to_string();
        assert!(e.contains("3 poses, the model's population 4"), "{e}");
    }
}

/// The real populations of ../shared/data, each fitted at the defaults, saved and opened.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn the_real_populations_open_as_the_same_fits_with_the_same_exports() {
    for name in ["horse-poses", "lion-poses", "horse-gallop"] {
        let test = "the_real_populations_open_as_the_same_fits_with_the_same_exports";
        let Some(dir) = common::shared_dir(&format!("data/{name}"), test) else { return };
        let pop = Population::new(posemfa::mesh::Sources::paths(&[&dir])).expect("loads");
        let (with, without) = round_trip(name, &pop, &Params::default());
        let raw = pop.n_shapes() * pop.n_vertices() * 12 + pop.faces.len() * 12;
        assert!((with as f64) <= 1.3 * raw as f64, "{name}: {with} bytes for {raw} of f32 points and u32 triangles");
        eprintln!(
            "{name}: {} x {}: {with} bytes with the poses ({:.2} x f32 points + u32 triangles), {without} without",
            pop.n_shapes(),
            pop.n_vertices(),
            with as f64 / raw as f64,
        );
    }
}
