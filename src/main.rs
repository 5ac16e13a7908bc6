fn main() {
    let ctx = aerial::vk::Context::new(&aerial::vk::ContextOptions { validate: true, device: None }).unwrap();
    println!("{:?}", ctx.device_info());
    let log = ctx.validation_log().unwrap();
    drop(ctx);
    println!("messages: {:?}", log.messages());
}
