//! PLY export of one mesh (ASCII or binary little endian), read back by [`crate::mesh::ply`].

/// The PLY encodings posemfa writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlyFormat {
    /// Text; coordinates printed in full (they read back bit for bit).
    Ascii,
    /// `binary_little_endian`, coordinates as float32.
    Binary,
}

/// One mesh as a PLY file: `vertex` (x, y, z) and `face` (`vertex_indices`, uchar count, int indices).
pub fn write_ply(positions: &[[f64; 3]], faces: &[[u32; 3]], format: PlyFormat, comment: &str) -> Vec<u8> {
    let mut out = Vec::with_capacity(64 + positions.len() * 40 + faces.len() * 24);
    let (fmt, ty) = match format {
        PlyFormat::Ascii => ("ascii", "double"),
        PlyFormat::Binary => ("binary_little_endian", "float"),
    };
    out.extend_from_slice(format!("ply\nformat {fmt} 1.0\n").as_bytes());
    for line in comment.lines() {
        out.extend_from_slice(format!("comment {line}\n").as_bytes());
    }
    out.extend_from_slice(
        format!(
            "element vertex {}\nproperty {ty} x\nproperty {ty} y\nproperty {ty} z\nelement face {}\n\
             property list uchar int vertex_indices\nend_header\n",
            positions.len(),
            faces.len()
        )
        .as_bytes(),
    );
    match format {
        PlyFormat::Ascii => {
            use std::fmt::Write as _;
            let mut s = String::with_capacity(positions.len() * 60 + faces.len() * 20);
            for p in positions {
                let _ = writeln!(s, "{:?} {:?} {:?}", p[0], p[1], p[2]);
            }
            for f in faces {
                let _ = writeln!(s, "3 {} {} {}", f[0], f[1], f[2]);
            }
            out.extend_from_slice(s.as_bytes());
        }
        PlyFormat::Binary => {
            for p in positions {
                for c in p {
                    out.extend_from_slice(&(*c as f32).to_le_bytes());
                }
            }
            for f in faces {
                out.push(3);
                for v in f {
                    out.extend_from_slice(&(*v as i32).to_le_bytes());
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_through_the_reader() {
        let p = vec![[0.1, -2.5e-7, 3.0], [1.0, 0.0, 0.0], [0.0, 1.0, 1.0 / 3.0]];
        let f = vec![[0, 1, 2], [2, 1, 0]];
        let a = crate::mesh::ply::parse_ply("a.ply", &write_ply(&p, &f, PlyFormat::Ascii, "made by a test")).unwrap();
        assert_eq!((a.positions.clone(), a.faces.clone()), (p.clone(), f.clone()));
        let b = crate::mesh::ply::parse_ply("b.ply", &write_ply(&p, &f, PlyFormat::Binary, "")).unwrap();
        assert_eq!(b.faces, f);
        assert_eq!(b.positions[2][2], f64::from(1.0f32 / 3.0));
    }
}
