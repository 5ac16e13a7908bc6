//! Validation is what docs/regression.md says: synchronization validation is on,
//! leaks at teardown are counted (on the error path too), best practices
//! are checked and every scene is clean under them, and each command fails
//! a run on a message.

use crate::common;

use aerial::render_run::{self, Misuse, RenderSettings, RunSource};
use aerial::vk::validation::{self, Validation, ValidationMessage, ALLOWED_MESSAGES};
use std::path::{Path, PathBuf};
use std::process::Output;

fn settings(validate: Validation) -> RenderSettings {
    RenderSettings {
        validate,
        ..common::validated_settings()
    }
}

fn messages_of(misuse: Misuse, validate: Validation) -> Vec<ValidationMessage> {
    match render_run::run(
        RunSource::ValidationCheck(misuse),
        &settings(validate),
        &mut || {},
    ) {
        Ok(run) => run.validation,
        Err(e) => panic!("the check itself failed: {e}"),
    }
}

fn show(messages: &[ValidationMessage]) -> String {
    messages
        .iter()
        .map(|m| m.to_string())
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn two_writes_without_a_barrier_are_a_sync_hazard() {
    for mode in [Validation::Sync, Validation::All] {
        let messages = messages_of(Misuse::SyncHazard, mode);
        assert!(
            messages
                .iter()
                .any(|m| m.id_name.starts_with("SYNC-HAZARD-WRITE-AFTER-WRITE")),
            "{mode:?}: no write-after-write hazard reported:\n{}",
            show(&messages)
        );
    }
}

#[test]
fn core_validation_alone_does_not_see_the_hazard() {
    // The hazard is only visible to the synchronization checks, so the
    // test above proves they are on, not that the core checks fire.
    let messages = messages_of(Misuse::SyncHazard, Validation::Core);
    assert!(messages.is_empty(), "{}", show(&messages));
}

#[test]
fn an_object_leaked_at_teardown_is_counted() {
    let messages = messages_of(Misuse::Leak, Validation::All);
    assert!(
        messages
            .iter()
            .any(|m| m.id_name.contains("vkDestroyDevice") && m.text.contains("VkSampler")),
        "the leaked sampler was not reported:\n{}",
        show(&messages)
    );
}

#[test]
fn a_leaked_object_is_counted_on_a_context_dropped_by_hand() {
    let ctx = common::validated_context();
    let log = ctx.validation_log().expect("validation enabled");
    ctx.leak_object_for_validation_check().unwrap();
    assert!(log.messages().is_empty(), "{}", show(&log.messages()));
    drop(ctx);
    assert!(
        log.messages().iter().any(|m| m.text.contains("VkSampler")),
        "{}",
        show(&log.messages())
    );
}

#[test]
fn a_failed_run_still_returns_the_validation_log() {
    let err = render_run::run(
        RunSource::ValidationCheck(Misuse::LeakThenFail),
        &settings(Validation::All),
        &mut || {},
    )
    .err()
    .expect("the run fails on purpose");
    assert!(
        err.validation
            .iter()
            .any(|m| m.id_name.contains("vkDestroyDevice")),
        "the leak was dropped on the error path: {err}"
    );
    assert!(err.to_string().contains("validation layer also reported"));
}

#[test]
fn without_validation_nothing_is_recorded() {
    let run = render_run::run(
        RunSource::ValidationCheck(Misuse::SyncHazard),
        &settings(Validation::Off),
        &mut || {},
    )
    .unwrap();
    assert!(run.validation.is_empty());
}

#[test]
fn the_shared_check_fails_on_any_message_and_lists_it() {
    assert!(validation::check(&[]).is_ok());
    let message = ValidationMessage {
        severity: "warning",
        id_name: "SOME-ID".into(),
        text: "something".into(),
    };
    let err = validation::check(std::slice::from_ref(&message)).unwrap_err();
    let text = err.to_string();
    assert!(
        text.contains("1 validation message") && text.contains("SOME-ID: something"),
        "{text}"
    );
}

#[test]
fn every_allow_list_entry_has_an_id_and_a_reason() {
    for (id, reason) in ALLOWED_MESSAGES {
        assert!(!id.is_empty() && reason.len() > 40, "{id}: {reason}");
    }
}

/// Every example, benchmark and sweep scene renders with no message under
/// each validation mode (best practices included), at a small size, and
/// so do the empty pass and tone-mapping an HDR image.
#[test]
fn every_scene_is_clean_under_every_mode() {
    for mode in [Validation::Core, Validation::BestPractices, Validation::All] {
        let run = render_run::run(
            RunSource::EmptyPass {
                width: 64,
                height: 36,
            },
            &settings(mode),
            &mut || {},
        )
        .unwrap();
        assert!(
            run.validation.is_empty(),
            "empty pass under {mode:?}:\n{}",
            show(&run.validation)
        );
        let hdr = aerial::render::Pixels {
            width: 8,
            height: 4,
            data: (0..8 * 4 * 4).map(|i| i as f32 * 0.05).collect(),
        };
        let run = render_run::run(
            RunSource::HdrImage(
                &hdr,
                aerial::scene::ToneMap {
                    operator: aerial::scene::ToneMapOperator::Reinhard,
                    exposure: aerial::scene::Exposure::Fixed(1.0),
                    bloom: None,
                },
            ),
            &settings(mode),
            &mut || {},
        )
        .unwrap();
        assert!(
            run.validation.is_empty(),
            "tonemap under {mode:?}:\n{}",
            show(&run.validation)
        );
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let mut scenes: Vec<PathBuf> = ["scenes", "bench", "sweep"]
        .iter()
        .flat_map(|d| std::fs::read_dir(root.join(d)).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 9, "{scenes:?}");
    for path in &scenes {
        let mut scene = aerial::scene::Scene::load(path).unwrap();
        scene.set_output_size(Some(64), Some(36)).unwrap();
        for mode in [Validation::Core, Validation::BestPractices, Validation::All] {
            let run = render_run::render(&scene, &settings(mode))
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(
                run.validation.is_empty(),
                "{} under {mode:?}:\n{}",
                path.display(),
                show(&run.validation)
            );
        }
    }
}

// The command line: each command fails a run on a message. The layer's
// vendor-specific best-practices checks (forced on through the loader's
// `VK_LAYER_ENABLES`, which the layer adds to what the application asks
// for) warn about things that are fine on lavapipe, so they are a real
// message the commands must refuse.

const VENDOR_CHECKS: &str = "VK_VALIDATION_FEATURE_ENABLE_BEST_PRACTICES_EXT:\
                             VALIDATION_CHECK_ENABLE_VENDOR_SPECIFIC_ALL";

use common::aerial;

fn assert_refused(out: &Output, what: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{what}: {stderr}");
    assert!(
        stderr.contains("validation message") && stderr.contains("BestPractices"),
        "{what}: {stderr}"
    );
}

#[test]
fn render_with_a_message_fails_and_writes_nothing() {
    let dir = common::fresh_dir("claims-validation", "render");
    let png = dir.join("out.png");
    let run = |env: Option<&str>| {
        let mut cmd = aerial();
        cmd.args([
            "render",
            "--validate",
            "--width",
            "32",
            "--height",
            "18",
            "--out",
        ])
        .arg(&png);
        if let Some(v) = env {
            cmd.env("VK_LAYER_ENABLES", v);
        }
        cmd.output().unwrap()
    };
    let out = run(Some(VENDOR_CHECKS));
    assert_refused(&out, "render");
    assert!(!png.exists());
    // The same run without the extra checks is clean and writes the file,
    // so it was the message that failed it.
    let out = run(None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(png.exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bench_and_sweep_with_a_message_fail() {
    let dir = common::fresh_dir("claims-validation", "bench");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bench/triangle.toml");
    let out = common::tiny_triangle_bench(1)
        .env("VK_LAYER_ENABLES", VENDOR_CHECKS)
        .output()
        .unwrap();
    assert_refused(&out, "bench");

    let out = aerial()
        .arg("sweep")
        .arg(&scene)
        .args([
            "--knob",
            "size=32x18",
            "--frames",
            "1",
            "--warmup",
            "0",
            "--validate=sync",
            "--out-dir",
        ])
        .arg(&dir)
        .env("VK_LAYER_ENABLES", VENDOR_CHECKS)
        .output()
        .unwrap();
    assert_refused(&out, "sweep");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn validate_takes_a_mode_and_rejects_others() {
    let out = aerial()
        .args(["render", "--validate=paranoid", "--out", "unused.png"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    for mode in ["core", "sync", "best-practices", "all"] {
        assert!(stderr.contains(mode), "{stderr}");
    }
    assert!(!stderr.contains("off"), "{stderr}");
}
