//! Limits of the device turn into clear errors, not crashes or validation
//! messages.

use crate::common;

use aerial::render_run;

#[test]
fn more_lights_than_a_uniform_block_holds_is_a_clear_error() {
    // Directional lights reach every object, so all of them land in the
    // object's block; 4096 of them (196 kB) exceed any device's minimum
    // uniform range and lavapipe's 64 kB.
    let mut toml = String::from(
        r#"
[camera]
eye = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
[[materials]]
name = "m"
kd = [0.5, 0.5, 0.5]
[[objects]]
name = "ball"
material = "m"
shape = { type = "sphere", radius = 1.0 }
"#,
    );
    for _ in 0..4096 {
        toml.push_str("[[lights]]\ntype = \"directional\"\ndirection = [0.0, 0.0, -1.0]\nintensity = 0.0001\n");
    }
    let scene = common::scene(&toml);
    let settings = common::validated_settings();
    let err = render_run::render(&scene, &settings)
        .err()
        .expect("rejected");
    // The failed run still returns the log, read after the device was
    // destroyed: the rejection left nothing behind for the layer to report.
    assert!(err.validation.is_empty(), "{err}");
    let err = err.to_string();
    assert!(err.contains("4096 lights"), "{err}");
}
