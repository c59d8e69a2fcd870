//! Point caches: `.pc2` (Maya/3ds Max/Blender "PointCache2", little endian) and `.mdd` (LightWave motion
//! designer data, big endian). A cache holds only positions, frame after frame, for the vertices of one base
//! mesh (OBJ, PLY or glTF) that gives the faces; every frame is one pose.
//!
//! Layouts:
//! - pc2: `"POINTCACHE2\0"`, i32 version (1), i32 points, f32 start frame, f32 sample rate, i32 samples, then
//!   samples x points x 3 f32 (little endian).
//! - mdd: i32 frames, i32 points, frames x f32 times (seconds), then frames x points x 3 f32 (big endian).
//!
//! The sizes in the header are checked against the file's length before anything is allocated; a file with
//! a different length, a negative count or a non-finite coordinate is an error that names the file, the
//! frame and the vertex where it can.

use crate::error::{Error, Result};

/// The frames of a point cache.
#[derive(Debug, Clone, PartialEq)]
pub struct PointCache {
    /// Number of vertices per frame.
    pub points: usize,
    /// `frames[f][j]`: vertex j in frame f.
    pub frames: Vec<Vec<[f64; 3]>>,
    /// The time of every frame as the file gives it: frame numbers (pc2: start + f / rate... see
    /// [`PointCache::describe`]) or seconds (mdd).
    pub times: Vec<f64>,
    /// "pc2" or "mdd".
    pub kind: &'static str,
}

impl PointCache {
    /// "48 frames of the point cache walk.pc2 (frames 1-48)" and the like.
    pub fn describe(&self, file: &str) -> String {
        let n = self.frames.len();
        match (self.times.first(), self.times.last()) {
            (Some(a), Some(b)) if self.kind == "mdd" => {
                format!("{n} frames of the point cache {file} (t = {a} s to {b} s)")
            }
            (Some(a), Some(b)) => format!("{n} frames of the point cache {file} (frames {a} to {b})"),
            _ => format!("{n} frames of the point cache {file}"),
        }
    }
}

fn err(file: &str, message: String) -> Error {
    Error::Mesh { format: crate::error::Format::PointCache, file: file.to_string(), line: 0, message }
}

fn frames_from(file: &str, data: &[u8], frames: usize, points: usize, big: bool) -> Result<Vec<Vec<[f64; 3]>>> {
    let mut out = Vec::with_capacity(frames);
    let mut chunks = data.chunks_exact(4).map(|c| {
        let b = [
            c.first().copied().unwrap_or(0),
            c.get(1).copied().unwrap_or(0),
            c.get(2).copied().unwrap_or(0),
            c.get(3).copied().unwrap_or(0),
        ];
        f64::from(if big { f32::from_be_bytes(b) } else { f32::from_le_bytes(b) })
    });
    for f in 0..frames {
        let mut frame = Vec::with_capacity(points);
        for j in 0..points {
            let p = [chunks.next(), chunks.next(), chunks.next()];
            let [Some(x), Some(y), Some(z)] = p else {
                return Err(err(file, format!("frame {f} is cut at vertex {j}; the file is cut: write it again")));
            };
            if !(x.is_finite() && y.is_finite() && z.is_finite()) {
                return Err(err(
                    file,
                    format!(
                        "frame {f}, vertex {j} has a non-finite coordinate ({x}, {y}, {z}); the simulation or the \
                         exporter wrote an invalid position: fix it there and write the cache again"
                    ),
                ));
            }
            frame.push([x, y, z]);
        }
        out.push(frame);
    }
    Ok(out)
}

/// Checks `header + frames * points * 12 (+ extra per frame) == len` in 64 bits.
fn check_size(file: &str, what: &str, len: usize, header: u64, frames: u64, points: u64, per_frame: u64) -> Result<()> {
    let need = points
        .checked_mul(12)
        .and_then(|b| b.checked_add(per_frame))
        .and_then(|b| b.checked_mul(frames))
        .and_then(|b| b.checked_add(header));
    match need {
        Some(n) if n == len as u64 => Ok(()),
        Some(n) => Err(err(
            file,
            format!(
                "its header says {frames} frames of {points} vertices, which take {n} bytes, but the file has {len}; \
                 the {what} file is cut or damaged: write it again"
            ),
        )),
        None => Err(err(
            file,
            format!(
                "its header says {frames} frames of {points} vertices, far more than the file holds; it is damaged"
            ),
        )),
    }
}

fn i32_at(b: &[u8], at: usize, big: bool) -> Option<i32> {
    let s: [u8; 4] = b.get(at..at + 4)?.try_into().ok()?;
    Some(if big { i32::from_be_bytes(s) } else { i32::from_le_bytes(s) })
}

fn f32_at(b: &[u8], at: usize, big: bool) -> Option<f32> {
    let s: [u8; 4] = b.get(at..at + 4)?.try_into().ok()?;
    Some(if big { f32::from_be_bytes(s) } else { f32::from_le_bytes(s) })
}

fn count(file: &str, what: &str, v: Option<i32>) -> Result<u64> {
    match v {
        Some(n) if n >= 0 => Ok(n as u64),
        Some(n) => Err(err(file, format!("the header gives {n} {what}, a negative count; the file is damaged"))),
        None => Err(err(file, "the file is shorter than its header; it is cut or not a point cache".into())),
    }
}

/// Parses a `.pc2` point cache.
pub fn parse_pc2(file: &str, bytes: &[u8]) -> Result<PointCache> {
    if !bytes.starts_with(b"POINTCACHE2\0") {
        return Err(err(
            file,
            "this is not a .pc2 point cache: it does not start with `POINTCACHE2`; write the cache again as PC2 (or \
             give the file the extension of its real format)"
                .into(),
        ));
    }
    let version = i32_at(bytes, 12, false);
    if version != Some(1) {
        return Err(err(file, format!("pc2 version {version:?} is not supported (only 1 exists)")));
    }
    let points = count(file, "points", i32_at(bytes, 16, false))?;
    let start = f32_at(bytes, 20, false).unwrap_or(0.0);
    let rate = f32_at(bytes, 24, false).unwrap_or(1.0);
    let samples = count(file, "samples", i32_at(bytes, 28, false))?;
    check_size(file, "pc2", bytes.len(), 32, samples, points, 0)?;
    if samples == 0 || points == 0 {
        return Err(err(file, format!("the cache holds {samples} frames of {points} vertices: nothing to fit")));
    }
    let (frames, points) = (samples as usize, points as usize);
    let data = bytes.get(32..).unwrap_or(&[]);
    let rate = if rate.is_finite() && rate > 0.0 { f64::from(rate) } else { 1.0 };
    let start = if start.is_finite() { start } else { 0.0 };
    let times = (0..frames).map(|f| f64::from(start) + f as f64 * rate).collect();
    Ok(PointCache { points, frames: frames_from(file, data, frames, points, false)?, times, kind: "pc2" })
}

/// Parses a `.mdd` point cache.
pub fn parse_mdd(file: &str, bytes: &[u8]) -> Result<PointCache> {
    let frames = count(file, "frames", i32_at(bytes, 0, true))?;
    let points = count(file, "points", i32_at(bytes, 4, true))?;
    check_size(file, "mdd", bytes.len(), 8, frames, points, 4)?;
    if frames == 0 || points == 0 {
        return Err(err(file, format!("the cache holds {frames} frames of {points} vertices: nothing to fit")));
    }
    let (frames, points) = (frames as usize, points as usize);
    let times = (0..frames).map(|f| f64::from(f32_at(bytes, 8 + 4 * f, true).unwrap_or(0.0))).collect();
    let data = bytes.get(8 + 4 * frames..).unwrap_or(&[]);
    Ok(PointCache { points, frames: frames_from(file, data, frames, points, true)?, times, kind: "mdd" })
}

/// Writes frames as a `.pc2` file (f32, little endian): start frame 0, one sample per frame.
pub fn write_pc2(frames: &[Vec<[f64; 3]>]) -> Vec<u8> {
    let points = frames.first().map_or(0, Vec::len);
    let mut b = Vec::with_capacity(32 + frames.len() * points * 12);
    b.extend_from_slice(b"POINTCACHE2\0");
    b.extend(1i32.to_le_bytes());
    b.extend((points as i32).to_le_bytes());
    b.extend(0f32.to_le_bytes());
    b.extend(1f32.to_le_bytes());
    b.extend((frames.len() as i32).to_le_bytes());
    for f in frames {
        for p in f {
            for c in p {
                b.extend((*c as f32).to_le_bytes());
            }
        }
    }
    b
}

/// Writes frames as a `.mdd` file (f32, big endian), frame f at time f / fps.
pub fn write_mdd(frames: &[Vec<[f64; 3]>], fps: f64) -> Vec<u8> {
    let points = frames.first().map_or(0, Vec::len);
    let mut b = Vec::with_capacity(8 + frames.len() * (4 + points * 12));
    b.extend((frames.len() as i32).to_be_bytes());
    b.extend((points as i32).to_be_bytes());
    for f in 0..frames.len() {
        b.extend(((f as f64 / fps) as f32).to_be_bytes());
    }
    for f in frames {
        for p in f {
            for c in p {
                b.extend((*c as f32).to_be_bytes());
            }
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames() -> Vec<Vec<[f64; 3]>> {
        vec![vec![[0.0, 0.0, 0.0], [1.0, 0.5, -2.0]], vec![[0.25, 0.0, 1.0], [1.0, 1.5, -2.0]], vec![[0.0; 3]; 2]]
    }

    #[test]
    fn pc2_and_mdd_round_trip() {
        let p = parse_pc2("a.pc2", &write_pc2(&frames())).unwrap();
        assert_eq!((p.points, p.frames.clone()), (2, frames()));
        assert_eq!(p.times, vec![0.0, 1.0, 2.0]);
        let m = parse_mdd("a.mdd", &write_mdd(&frames(), 24.0)).unwrap();
        assert_eq!(m.frames, frames());
        assert!((m.times[2] - 2.0 / 24.0).abs() < 1e-7);
        assert!(p.describe("a.pc2").starts_with("3 frames of the point cache a.pc2"));
    }

    #[test]
    fn sizes_are_checked_before_allocating() {
        let mut b = write_pc2(&frames());
        b[28..32].copy_from_slice(&i32::MAX.to_le_bytes());
        let e = parse_pc2("a.pc2", &b).unwrap_err().to_string();
        assert!(e.starts_with("file a.pc2: ") && e.contains("2147483647 frames") && e.contains("cut"), "{e}");
        let b = write_pc2(&frames());
        let e = parse_pc2("a.pc2", &b[..b.len() - 1]).unwrap_err().to_string();
        assert!(e.contains("the file has 103"), "{e}");
        let mut b = write_mdd(&frames(), 24.0);
        b[4..8].copy_from_slice(&(-3i32).to_be_bytes());
        let e = parse_mdd("a.mdd", &b).unwrap_err().to_string();
        assert!(e.contains("negative"), "{e}");
        let e = parse_mdd("a.mdd", b"\0\0").unwrap_err().to_string();
        assert!(e.contains("shorter than its header"), "{e}");
        let e = parse_pc2("a.pc2", b"v 0 0 0\n").unwrap_err().to_string();
        assert!(e.contains("not a .pc2"), "{e}");
        let mut f = frames();
        f[1][1][2] = f64::NAN;
        let e = parse_mdd("a.mdd", &write_mdd(&f, 24.0)).unwrap_err().to_string();
        assert!(e.contains("frame 1, vertex 1"), "{e}");
    }
}
