//! A command that is not a telecommand is answered at once with a
//! rejection naming where and what is wrong, and nothing reaches the
//! executive.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::time::Duration;
use stucco_core::{Ack, Reply, Stamp};
use stucco_link::{LinkConfig, RobotLink, keys, open};
use zenoh::Wait;

/// The robot's reason for refusing `payload` sent to `stucco/r1/cmd`
/// (nothing may reach the executive).
fn refusal(payload: Vec<u8>) -> String {
    // One session with no endpoints delivers to itself.
    let session = open(&LinkConfig::default()).unwrap();
    let mut robot = RobotLink::new(&session, "r1").unwrap();
    let replies = session
        .get(keys::cmd("r1"))
        .payload(payload)
        .timeout(Duration::from_secs(2))
        .wait()
        .unwrap();
    // The robot's loop takes its commands: none valid, one answered.
    let mut taken = Vec::new();
    for _ in 0..100 {
        taken.extend(robot.take_commands(Stamp::ZERO));
        std::thread::sleep(Duration::from_millis(10));
        if let Ok(Some(reply)) = replies.try_recv() {
            let ack: Ack =
                serde_json::from_slice(&reply.result().unwrap().payload().to_bytes()).unwrap();
            let Reply::Rejected { reason } = ack.reply else {
                panic!("{ack:?}");
            };
            assert!(taken.is_empty());
            assert!(ack.id.is_empty());
            return reason;
        }
    }
    panic!("no reply to a malformed command");
}

#[test]
fn a_malformed_command_is_rejected_with_line_and_column() {
    let reason = refusal(
        b"{\"id\": \"c1\",\n \"operator\": \"ann\", \"issued\": 0,\n \"deadline\": \"soon\"}"
            .to_vec(),
    );
    assert!(reason.contains("not a telecommand"), "{reason}");
    assert!(reason.contains("line 3"), "{reason}");
}

/// A megabyte of command is refused unread, and its reason does not echo
/// it.
#[test]
fn an_oversized_command_is_refused_unread() {
    let huge = format!(
        "{{\"id\": \"{}\", \"operator\": \"ann\", \"issued\": 0, \"deadline\": 1, \"command\": {{\"type\": \"stop\"}}}}",
        "x".repeat(1 << 20)
    );
    let reason = refusal(huge.into_bytes());
    assert!(reason.contains("at most 4096"), "{reason}");
    assert!(reason.len() < 200, "{} bytes", reason.len());
}
