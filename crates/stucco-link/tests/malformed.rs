//! A command that is not a telecommand is answered at once with a
//! rejection naming where and what is wrong, and nothing reaches the
//! executive.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::time::Duration;
use stucco_core::{Ack, Reply, Stamp};
use stucco_link::{LinkConfig, RobotLink, keys, open};
use zenoh::Wait;

#[test]
fn a_malformed_command_is_rejected_with_line_and_column() {
    // One session with no endpoints delivers to itself.
    let session = open(&LinkConfig::default()).unwrap();
    let mut robot = RobotLink::new(&session, "r1").unwrap();
    let replies = session
        .get(keys::cmd("r1"))
        .payload(
            "{\"id\": \"c1\",\n \"operator\": \"ann\", \"issued\": 0,\n \"deadline\": \"soon\"}",
        )
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
            assert!(reason.contains("not a telecommand"), "{reason}");
            assert!(reason.contains("line 3"), "{reason}");
            assert!(taken.is_empty());
            return;
        }
    }
    panic!("no reply to a malformed command");
}
