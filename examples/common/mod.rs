//! What the scale-scene examples (`sphere_grid`, `instance_field`) share:
//! their command line, `N OUT.toml [auto]`.

/// The parsed command line: the object count, the output path, and the
/// object lines that ask for `tessellation = "auto"` (empty without it).
pub struct ScaleArgs {
    pub count: usize,
    pub out: String,
    pub tessellation: &'static str,
}

/// Reads `N OUT.toml [auto]`, or prints `usage` and exits with status 2.
pub fn scale_args(name: &str, usage: &str) -> ScaleArgs {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(count), Some(out)) = (
        args.first().and_then(|n| n.parse::<usize>().ok()),
        args.get(1),
    ) else {
        eprintln!("usage: {name} N OUT.toml [auto]  ({usage})");
        std::process::exit(2);
    };
    let tessellation = match args.get(2).map(String::as_str) {
        None => "",
        Some("auto") => "tessellation = \"auto\"\n",
        Some(other) => {
            eprintln!("{name}: the third argument is 'auto' or nothing, not '{other}'");
            std::process::exit(2);
        }
    };
    ScaleArgs {
        count,
        out: out.clone(),
        tessellation,
    }
}
