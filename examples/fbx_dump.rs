//! Prints the node tree of a binary FBX file (names, scalar properties, array lengths), for debugging.
//! Usage: cargo run --example fbx_dump -- FILE.fbx [MAX_DEPTH]
fn show(n: &posemfa::mesh::fbx_tree::Node, depth: usize, max: usize) {
    use posemfa::mesh::fbx_tree::Prop;
    let props: Vec<String> = n
        .props
        .iter()
        .map(|p| match p {
            Prop::Str(s) => format!("{:?}", s.replace('\0', "\\0").replace('\u{1}', "\\1")),
            Prop::Int(v) => v.to_string(),
            Prop::Float(v) => v.to_string(),
            Prop::Bool(b) => b.to_string(),
            Prop::Raw(n) => format!("raw[{n}]"),
            other => {
                let v = other.to_f64s().unwrap_or_default();
                format!("array[{}] {:?}", v.len(), &v[..v.len().min(6)])
            }
        })
        .collect();
    println!("{}{}: {}", "  ".repeat(depth), n.name, props.join(", "));
    if depth < max {
        for c in &n.children {
            show(c, depth + 1, max);
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).expect("usage: fbx_dump FILE.fbx [MAX_DEPTH]");
    let max = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(99);
    let bytes = std::fs::read(path).expect("cannot read the file");
    match posemfa::mesh::fbx_tree::parse(path, &bytes, 1 << 32) {
        Ok(t) => {
            println!("FBX {}", t.version);
            for n in &t.nodes {
                show(n, 0, max);
            }
        }
        Err(e) => println!("{e}"),
    }
}
