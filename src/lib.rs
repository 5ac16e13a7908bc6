//! `aerial`: an explicit, headless Vulkan renderer.
//!
//! Data flows one way: a [`scene::Scene`] (TOML) is planned into the passes
//! and resources it needs ([`render::FramePlan`]), built on the GPU through
//! the thin RAII layer in [`vk`], recorded once into a command buffer,
//! submitted per frame, and read back as images and per-pass timings.

pub mod atmosphere;
pub mod bench;
pub mod budget;
pub mod callgrind;
pub mod child_process;
pub mod image_io;
pub mod interrupt;
pub mod mesh;
pub mod render;
pub mod render_run;
pub mod report;
pub mod safe_files;
pub mod scene;
pub mod sweep;
pub mod viewer;
pub mod vk;

/// SPIR-V of every shader in `glsl/`, compiled by `build.rs`: one
/// [`shaders::ShaderVariants`] per stage file, holding every combination of
/// the feature flags the file declares.
pub mod shaders {
    /// Every compiled combination of one shader file's feature flags.
    pub struct ShaderVariants {
        /// The source file, e.g. `object.frag`.
        pub file: &'static str,
        /// The flags the file declares (`// feature: NAME`), in order.
        pub features: &'static [&'static str],
        /// SPIR-V per combination; bit i of the index enables `features[i]`.
        /// Empty for a combination the file's rules leave out
        /// (`// requires:`, `// excludes:`, see `build.rs`).
        pub spirv: &'static [&'static [u8]],
    }

    impl ShaderVariants {
        /// The variant with exactly the `enabled` flags this file declares.
        /// Flags the file does not declare are ignored, so a pass can ask
        /// the vertex and fragment stage for the same set.
        pub fn spirv(&self, enabled: &[&str]) -> &'static [u8] {
            let index = self
                .features
                .iter()
                .enumerate()
                .filter(|(_, f)| enabled.contains(f))
                .fold(0, |acc, (i, _)| acc | (1 << i));
            let spirv = self.spirv[index];
            // A pass asking for a combination the rules leave out is a bug
            // in the pass, not in any input.
            assert!(
                !spirv.is_empty(),
                "{}: the combination {enabled:?} is not compiled",
                self.file
            );
            spirv
        }

        /// The variant with no feature enabled.
        pub fn base(&self) -> &'static [u8] {
            self.spirv[0]
        }
    }

    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}
