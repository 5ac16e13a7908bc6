//! The validation messenger is live: a deliberate misuse is counted, and
//! a clean context reports nothing.

use aerial::vk::{Context, ContextOptions};

fn validated() -> std::sync::Arc<Context> {
    Context::new(&ContextOptions {
        validate: aerial::vk::validation::Validation::All,
        device: None,
        display: None,
        ..Default::default()
    })
    .expect("a Vulkan device with the validation layer")
}

#[test]
fn a_deliberate_misuse_is_counted() {
    let ctx = validated();
    let log = ctx.validation_log().expect("validation enabled");
    ctx.misuse_api_for_validation_check().unwrap();
    drop(ctx);
    let messages = log.messages();
    assert!(
        messages
            .iter()
            .any(|m| m.id_name.contains("anisotropy") || m.text.contains("anisotropy")),
        "the misuse was not reported: {messages:?}"
    );
}

#[test]
fn a_clean_context_reports_nothing() {
    let ctx = validated();
    let log = ctx.validation_log().unwrap();
    drop(ctx);
    assert!(log.messages().is_empty(), "{:?}", log.messages());
}
