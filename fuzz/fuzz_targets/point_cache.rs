//! bytes -> posemfa::mesh::cache::parse_pc2 / parse_mdd, then mesh::load with a one-triangle base mesh.
//!
//! Input layout: byte 0 picks the format (even: .pc2, odd: .mdd); the rest is the file. A loaded cache has
//! exactly the frames x points its header gives (which the file's length must match), finite coordinates,
//! one time per frame, and writes back to the same frames; mesh::load with a 3-vertex OBJ base either gives
//! one pose per frame (when the cache has 3 points) or refuses with the cache named. Never a panic, never
//! an allocation from an unchecked header field.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posemfa::mesh::cache::{parse_mdd, parse_pc2, write_pc2};
use posemfa::mesh::load::load;
use posemfa::error::Format;
use posemfa::Error;

const BASE: &[u8] = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

fuzz_target!(|data: &[u8]| {
    let Some((&cfg, file)) = data.split_first() else { return };
    let (name, parsed) = if cfg % 2 == 0 { ("fuzz.pc2", parse_pc2("fuzz.pc2", file)) } else { ("fuzz.mdd", parse_mdd("fuzz.mdd", file)) };
    match &parsed {
        Ok(cache) => {
            let header = if cfg % 2 == 0 { 32 } else { 8 + 4 * cache.frames.len() };
            assert_eq!(header + cache.frames.len() * cache.points * 12, file.len(), "frames x points do not match the length");
            assert_eq!(cache.times.len(), cache.frames.len());
            assert!(cache.frames.iter().all(|f| f.len() == cache.points));
            assert!(cache.frames.iter().flatten().flatten().all(|c| c.is_finite()));
            let again = parse_pc2("again.pc2", &write_pc2(&cache.frames)).expect("a cache written back reads");
            assert_eq!(again.frames, cache.frames);
        }
        Err(Error::Mesh { format: Format::PointCache, file, message, .. }) => {
            assert_eq!(file, name);
            assert!(!message.is_empty());
        }
        Err(e) => panic!("the point cache reader returned an error that is not a point cache reader's: {e:?}"),
    }
    let loaded = load(vec![(name.to_string(), file.to_vec()), ("base.obj".to_string(), BASE.to_vec())]);
    match (parsed, loaded) {
        (Ok(cache), Ok(l)) => {
            assert_eq!(cache.points, 3);
            assert_eq!(l.poses.len(), cache.frames.len());
            assert!(l.source.contains(name) && l.source.contains("base.obj"), "{}", l.source);
        }
        (Ok(cache), Err(errors)) => {
            assert_ne!(cache.points, 3, "a 3-point cache over a 3-vertex base was refused: {errors:?}");
            assert!(errors.iter().all(|e| e.to_string().contains(name)), "{errors:?}");
        }
        (Err(_), Ok(_)) => panic!("mesh::load accepted a cache its reader refused"),
        (Err(_), Err(errors)) => assert!(!errors.is_empty()),
    }
});
