//! The validation messenger is live: a deliberate misuse is counted, and
//! a clean context reports nothing.

use crate::common;

#[test]
fn a_deliberate_misuse_is_counted() {
    let ctx = common::validated_context();
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
    let ctx = common::validated_context();
    let log = ctx.validation_log().unwrap();
    drop(ctx);
    assert!(log.messages().is_empty(), "{:?}", log.messages());
}
