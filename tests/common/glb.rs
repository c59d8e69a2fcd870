//! A .glb taken apart and put together again, for tests that lay out or damage a file by hand.

use serde_json::{json, Value};

/// The JSON document and BIN chunk of a .glb.
pub fn split(glb: &[u8]) -> (Value, Vec<u8>) {
    let jlen = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let doc: Value = serde_json::from_slice(&glb[20..20 + jlen]).unwrap();
    let at = 20 + jlen;
    let blen = u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
    (doc, glb[at + 8..at + 8 + blen].to_vec())
}

/// A .glb of a JSON document and a BIN chunk (buffer 0's byteLength set to the padded chunk).
pub fn join(mut doc: Value, mut bin: Vec<u8>) -> Vec<u8> {
    pad(&mut bin, 0);
    doc["buffers"][0]["byteLength"] = json!(bin.len());
    container(serde_json::to_vec(&doc).unwrap(), bin)
}

/// A .glb of JSON text as it is (which a `Value` could not always hold) and a BIN chunk, each padded to 4 bytes.
pub fn container(mut text: Vec<u8>, mut bin: Vec<u8>) -> Vec<u8> {
    pad(&mut text, b' ');
    pad(&mut bin, 0);
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + 8 + text.len() + 8 + bin.len()) as u32).to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(text);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

fn pad(bytes: &mut Vec<u8>, with: u8) {
    while bytes.len() % 4 != 0 {
        bytes.push(with);
    }
}
