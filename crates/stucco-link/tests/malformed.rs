//! A command that is not a telecommand is answered at once with a
//! rejection naming where and what is wrong, and nothing reaches the
//! executive.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::time::Duration;
use stucco_core::{Ack, Reply, Stamp};
use stucco_link::{LinkConfig, RobotLink, keys, open};
use zenoh::Wait;

/// The robot's reason for refusing `payload` sent by `ann` to
/// `stucco/r1/cmd/ann` (nothing may reach the executive), and what the
/// robot logged of it.
fn refusal(payload: Vec<u8>) -> String {
    refusal_logged(payload).0
}

fn refusal_logged(payload: Vec<u8>) -> (String, Vec<stucco_link::Denial>) {
    // One session with no endpoints delivers to itself.
    let session = open(&LinkConfig::default()).unwrap();
    let mut robot = RobotLink::new(&session, "r1").unwrap();
    let replies = session
        .get(keys::command("r1", "ann"))
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
            return (reason, robot.denials());
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

/// A command sent by `ann` (on her key) that names `vic` as its operator
/// is refused, and the robot keeps who tried and whom they claimed to be.
#[test]
fn a_command_claiming_another_operator_is_refused_and_logged() {
    let (reason, logged) = refusal_logged(
        br#"{"id": "c1", "operator": "vic", "issued": 0, "deadline": 1000000000, "command": {"type": "status"}}"#
            .to_vec(),
    );
    assert!(
        reason.contains("names \"vic\" but was sent as \"ann\""),
        "{reason}"
    );
    assert_eq!(logged.len(), 1, "{logged:?}");
    assert_eq!(logged[0].subject, "ann");
    assert!(logged[0].action.contains("vic"), "{:?}", logged[0]);
}
