//! One shader stage's feature flags, its rules, and the compilation of
//! every combination they allow.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::layout::Layouts;

/// Compiles stages with shared options.
pub struct Compiler {
    pub compiler: shaderc::Compiler,
    pub root: PathBuf,
    /// Searched, in order, after the including file's own folder.
    pub include_dirs: Vec<PathBuf>,
    pub out: PathBuf,
}

/// A stage file's declared flags and rules.
struct Flags {
    features: Vec<String>,
    /// (flag bit, other flag bit, whether the rule is `requires`).
    rules: Vec<(u32, u32, bool)>,
}

impl Flags {
    fn parse(name: &str, source: &str) -> Flags {
        let features: Vec<String> = source
            .lines()
            .filter_map(|line| line.trim().strip_prefix("// feature:"))
            .flat_map(|rest| rest.split_whitespace().map(str::to_string))
            .collect();
        let bit = |flag: &str| {
            let i = features
                .iter()
                .position(|f| f == flag)
                .unwrap_or_else(|| panic!("{name}: rule names an undeclared feature {flag}"));
            1u32 << i
        };
        let rules = source
            .lines()
            .filter_map(|line| {
                let line = line.trim();
                let (rest, requires) = match line.strip_prefix("// requires:") {
                    Some(rest) => (rest, true),
                    None => (line.strip_prefix("// excludes:")?, false),
                };
                let flags: Vec<&str> = rest.split_whitespace().collect();
                assert!(
                    flags.len() == 2,
                    "{name}: a rule names two features: {line}"
                );
                Some((bit(flags[0]), bit(flags[1]), requires))
            })
            .collect();
        let flags = Flags { features, rules };
        let count = flags.combinations().filter(|&c| flags.compiled(c)).count();
        // A budget on build time and binary size (every variant is
        // compiled and embedded), not a limit of the format.
        assert!(
            flags.features.len() <= 8 && count <= 80,
            "{name}: at most 80 variants ({count} from {} feature flags)",
            flags.features.len()
        );
        flags
    }

    /// Every combination; bit i enables `features[i]`.
    fn combinations(&self) -> std::ops::Range<u32> {
        0..1u32 << self.features.len()
    }

    /// Whether the rules keep `combination`.
    fn compiled(&self, combination: u32) -> bool {
        self.rules
            .iter()
            .all(|&(a, b, requires)| combination & a == 0 || (combination & b != 0) == requires)
    }

    fn defines(&self, combination: u32) -> Vec<&String> {
        self.features
            .iter()
            .enumerate()
            .filter(|(i, _)| combination & (1 << i) != 0)
            .map(|(_, f)| f)
            .collect()
    }
}

impl Compiler {
    /// Compiles every allowed combination of a stage file and returns its
    /// generated Rust (the flag type and the `ShaderVariants` constant);
    /// `None` for a file that is not a stage, `Err` when GLSL failed to
    /// compile (the errors are printed).
    pub fn stage(&self, path: &Path, layouts: &mut Layouts) -> Option<Result<String, ()>> {
        let kind = stage_of(path)?;
        let source = std::fs::read_to_string(path).expect("readable shader");
        let name = path.file_name()?.to_string_lossy().into_owned();
        let display = path
            .strip_prefix(&self.root)
            .unwrap_or(path)
            .to_string_lossy()
            .into_owned();
        let flags = Flags::parse(&name, &source);
        let constant = constant_name(&name);
        let mut spirv_files = Vec::new();
        let mut failed = false;
        for combination in flags.combinations() {
            if !flags.compiled(combination) {
                // Left out by a rule: no SPIR-V.
                spirv_files.push(None);
                continue;
            }
            let defines = flags.defines(combination);
            match self.compile(&source, kind, &display, &defines) {
                Ok(spirv) => {
                    layouts.add(&display, &spirv);
                    let file = format!("{constant}_{combination}.spv");
                    std::fs::write(self.out.join(&file), &spirv).expect("write SPIR-V");
                    spirv_files.push(Some(file));
                }
                Err(e) => {
                    eprintln!("GLSL error in {display} (features {defines:?}):\n{e}");
                    failed = true;
                }
            }
        }
        if failed {
            return Some(Err(()));
        }
        Some(Ok(generated(&name, &flags.features, &spirv_files)))
    }

    fn compile(
        &self,
        source: &str,
        kind: shaderc::ShaderKind,
        display: &str,
        defines: &[&String],
    ) -> Result<Vec<u8>, shaderc::Error> {
        let mut options = shaderc::CompileOptions::new().expect("options");
        options.set_target_env(
            shaderc::TargetEnv::Vulkan,
            shaderc::EnvVersion::Vulkan1_2 as u32,
        );
        options.set_optimization_level(shaderc::OptimizationLevel::Performance);
        options.set_generate_debug_info();
        for d in defines {
            options.add_macro_definition(d, Some("1"));
        }
        let include_dirs = self.include_dirs.clone();
        options.set_include_callback(move |requested, _ty, requester, _depth| {
            let from = Path::new(requester).parent().unwrap_or(Path::new("."));
            let candidates = std::iter::once(from.join(requested))
                .chain(include_dirs.iter().map(|d| d.join(requested)));
            for c in candidates {
                if let Ok(content) = std::fs::read_to_string(&c) {
                    return Ok(shaderc::ResolvedInclude {
                        resolved_name: c.to_string_lossy().into_owned(),
                        content,
                    });
                }
            }
            Err(format!("cannot find include \"{requested}\""))
        });
        let artifact =
            self.compiler
                .compile_into_spirv(source, kind, display, "main", Some(&options))?;
        if artifact.get_num_warnings() > 0 {
            println!("cargo:warning={}", artifact.get_warning_messages());
        }
        Ok(artifact.as_binary_u8().to_vec())
    }
}

/// The Rust for one stage: its flag type and its variants.
fn generated(name: &str, features: &[String], spirv_files: &[Option<String>]) -> String {
    let constant = constant_name(name);
    let flag_type = if features.is_empty() {
        "NoFeatures".to_string()
    } else {
        flag_type_name(name)
    };
    let mut out = String::new();
    if !features.is_empty() {
        let flags: Vec<String> = features
            .iter()
            .enumerate()
            .map(|(i, f)| format!("{f} = {i}"))
            .collect();
        writeln!(
            out,
            "feature_flags!({flag_type}, {name:?}, [{}]);",
            flags.join(", ")
        )
        .expect("string write");
    }
    let includes: Vec<String> = spirv_files
        .iter()
        .map(|f| match f {
            Some(f) => format!("include_bytes!(concat!(env!(\"OUT_DIR\"), \"/{f}\"))"),
            None => "&[]".to_string(),
        })
        .collect();
    writeln!(
        out,
        "pub const {constant}: ShaderVariants<{flag_type}> = ShaderVariants::new({name:?}, &[{}]);",
        includes.join(", ")
    )
    .expect("string write");
    out
}

fn stage_of(path: &Path) -> Option<shaderc::ShaderKind> {
    match path.extension()?.to_str()? {
        "vert" => Some(shaderc::ShaderKind::Vertex),
        "frag" => Some(shaderc::ShaderKind::Fragment),
        "comp" => Some(shaderc::ShaderKind::Compute),
        _ => None,
    }
}

/// `object.frag` → `OBJECT_FRAG`.
fn constant_name(file: &str) -> String {
    file.replace(['.', '-'], "_").to_uppercase()
}

/// `object.frag` → `ObjectFragFeatures`.
fn flag_type_name(file: &str) -> String {
    let mut name: String = file
        .split(['.', '-', '_'])
        .map(|word| {
            let mut chars = word.chars();
            match chars.next() {
                Some(first) => first.to_uppercase().chain(chars).collect(),
                None => String::new(),
            }
        })
        .collect();
    name.push_str("Features");
    name
}
