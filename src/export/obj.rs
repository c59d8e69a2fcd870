//! OBJ export: `v` lines in vertex order, then `f` lines (1-based), after a `#` comment header.
//!
//! Coordinates are written with Rust's shortest round-trip formatting of f64 (`{}`), so parsing a written
//! file back gives the very same f64 values (no exponent notation; `-0` for negative zero). Non-finite values
//! would be written as `NaN` / `inf`, which OBJ readers (posemfa's included) reject: pass finite positions.

use std::fmt::Write;

/// The OBJ text of a triangle mesh. Every line of `header` becomes a `# ` comment line (an empty header
/// writes no comment).
pub fn write_obj(positions: &[[f64; 3]], faces: &[[u32; 3]], header: &str) -> String {
    let mut out = String::with_capacity(header.len() + 8 + positions.len() * 60 + faces.len() * 24);
    for line in header.lines() {
        out.push('#');
        if !line.is_empty() {
            out.push(' ');
            out.push_str(line);
        }
        out.push('\n');
    }
    for p in positions {
        // writing into a String cannot fail
        let _ = writeln!(out, "v {} {} {}", p[0], p[1], p[2]);
    }
    for f in faces {
        let _ = writeln!(out, "f {} {} {}", u64::from(f[0]) + 1, u64::from(f[1]) + 1, u64::from(f[2]) + 1);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_and_exact_floats() {
        let pos = [[0.1, -2.5e-12, 1.0 / 3.0], [1e20, -0.0, 123456.789]];
        let text = write_obj(&pos, &[[0, 1, 0]], "first\n\nsecond");
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "# first");
        assert_eq!(lines[1], "#");
        assert_eq!(lines[2], "# second");
        assert_eq!(lines[5], "f 1 2 1");
        assert_eq!(lines.len(), 6);
        for (k, p) in pos.iter().enumerate() {
            let v: Vec<f64> = lines[3 + k].split_whitespace().skip(1).map(|t| t.parse().unwrap()).collect();
            assert_eq!(v.len(), 3);
            for d in 0..3 {
                assert_eq!(v[d].to_bits(), p[d].to_bits(), "{}", lines[3 + k]);
            }
        }
        assert!(!lines[3..5].iter().any(|l| l.contains('e')), "no exponent notation: {text}");
        assert_eq!(write_obj(&[], &[], ""), "");
        assert!(write_obj(&[[0.0; 3]], &[[u32::MAX, 0, 0]], "").ends_with("f 4294967296 1 1\n"));
    }
}
