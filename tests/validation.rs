//! The validation check can fail. A deliberately missing barrier is reported, both in a
//! test-only pass (a write-after-write hazard that only synchronization validation sees) and
//! in the real renderer (a skipped layout transition). Without these, "zero validation
//! errors" in the other tests would prove nothing.
mod common;

use prism::gpu::{vk, Access, Buffer, MemoryLocation};
use prism::graph::FrameGraph;

/// Two test-only passes that both write one buffer (transfer fills); the graph would put a
/// barrier between them. Returns the validation error count.
fn two_writes(skip_barrier: bool) -> Option<u64> {
    let ctx = common::context(true);
    if !ctx.info.sync_validation {
        assert!(!common::under_ci(), "CI needs the validation layer");
        eprintln!("synchronization validation unavailable: skipping");
        return None;
    }
    let buffer =
        Buffer::new(&ctx, "test_data", 256, vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuOnly).unwrap();
    let mut graph = FrameGraph::new();
    let id = graph.register_buffer(&buffer);
    if skip_barrier {
        graph.skip_buffer_barriers_for_tests(id);
    }
    let target = &buffer;
    ctx.one_shot(|cmd| {
        let mut frame = graph.frame();
        for (name, value) in [("first_write", 1), ("second_write", 2)] {
            frame.pass(name).write(id, Access::TransferWrite).record(move |cmd| cmd.fill_buffer(target, value));
        }
        frame.execute(cmd, None);
    })
    .unwrap();
    ctx.wait_idle().unwrap();
    let errors = ctx.validation_errors();
    drop((graph, buffer));
    if skip_barrier {
        // The hazard's error is what this run is for: no teardown check.
        drop(ctx.unchecked());
    } else {
        common::assert_clean_teardown(ctx);
    }
    Some(errors)
}

#[test]
fn missing_barrier_in_a_test_pass_is_reported_by_sync_validation() {
    if !common::in_own_process() {
        return;
    }
    if let Some(errors) = two_writes(true) {
        assert!(errors > 0, "a write-after-write hazard without a barrier must be reported");
    }
}

#[test]
fn the_same_passes_with_the_graph_barriers_are_clean() {
    if !common::in_own_process() {
        return;
    }
    if let Some(errors) = two_writes(false) {
        assert_eq!(errors, 0);
    }
}

/// Under CI, whatever `CI` is set to, a missing validation layer fails the GPU tests (here
/// the test above, run again with the layer search path pointing nowhere).
#[test]
fn a_missing_validation_layer_fails_under_ci() {
    if !common::in_own_process() {
        return;
    }
    for ci in ["1", "true", "woodpecker"] {
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args(["--exact", "the_same_passes_with_the_graph_barriers_are_clean", "--test-threads", "1"])
            .env("CI", ci)
            .env("VK_LAYER_PATH", "/nonexistent")
            .env_remove("VK_ADD_LAYER_PATH")
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "CI={ci}: passed without the validation layer:\n{text}");
        assert!(text.contains("VK_LAYER_KHRONOS_validation is not installed"), "CI={ci}:\n{text}");
    }
}

/// Skip the G-buffer normal target's barriers in the real renderer: the gbuffer pass then
/// renders into an image still in UNDEFINED layout, and the validation layer must say so.
#[test]
fn skipped_transition_in_the_renderer_is_reported() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false).unchecked();
    if !ctx.info.validation {
        return;
    }
    let scene = common::scene("sphere_env", 32, &[]);
    let mut r = prism::renderer::Renderer::new(&ctx, &scene).unwrap();
    r.skip_barriers_for_tests("gbuf_normal");
    r.render_frame().unwrap();
    r.finish().unwrap();
    drop(r);
    assert!(ctx.validation_errors() > 0, "a missing layout transition must be reported");
}

/// An object still alive when the device is destroyed is reported then, after every other
/// check: the test context's drop, which every GPU test's context goes through, sees it
/// once the device is gone and fails the test.
#[test]
fn a_leaked_object_is_reported_at_teardown() {
    if !common::in_own_process() {
        return;
    }
    let ctx = common::context(false);
    if !ctx.info.validation {
        return;
    }
    ctx.leak_a_fence_for_tests().unwrap();
    common::assert_no_validation_errors(&ctx);
    let log = ctx.validation_log();
    let failed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(move || drop(ctx)));
    let message = failed.expect_err("a fence left alive at vkDestroyDevice must fail the test");
    let message = message.downcast_ref::<String>().cloned().unwrap_or_default();
    assert!(message.contains("validation errors at teardown"), "{message}");
    assert!(log.errors() > 0);
    assert!(log.messages().iter().any(|m| m.contains("VkFence")), "{:?}", log.messages());
}
