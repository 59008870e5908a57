//! Who may command: zenoh's own user/password authentication and access
//! control in the robot's embedded peer. An operator may command and
//! watch; a viewer may watch, and its commands never reach the robot.

use std::path::Path;
use std::time::Duration;
use stucco_cli::{LinkConfig, Operator};
use stucco_core::{Command, Reply};

/// The robot's zenoh configuration: users from `dictionary`, operators
/// `ann`, viewers `vic`, everything else denied.
fn robot_config(dictionary: &Path) -> String {
    let watch = r#"["stucco/r1/state", "stucco/r1/events", "stucco/r1/acks", "stucco/r1/heartbeat", "stucco/r1/info", "stucco/r1/map", "stucco/r1/scan", "stucco/r1/coverage"]"#;
    format!(
        r#"{{
  mode: "peer",
  transport: {{ auth: {{ usrpwd: {{ user: "r1", password: "robot-secret", dictionary_file: "{dict}" }} }} }},
  access_control: {{
    enabled: true,
    default_permission: "deny",
    rules: [
      {{ id: "command", messages: ["put", "delete", "declare_subscriber", "query", "reply", "declare_queryable",
                   "liveliness_token", "liveliness_query", "declare_liveliness_subscriber"],
         flows: ["ingress", "egress"], permission: "allow", key_exprs: ["stucco/r1/**"] }},
      {{ id: "watch", messages: ["put", "declare_subscriber", "query", "reply", "declare_queryable",
                   "liveliness_token", "liveliness_query", "declare_liveliness_subscriber"],
         flows: ["ingress", "egress"], permission: "allow", key_exprs: {watch} }},
      {{ id: "see-commands", messages: ["declare_queryable"], flows: ["egress"], permission: "allow",
         key_exprs: ["stucco/r1/cmd"] }},
    ],
    subjects: [
      {{ id: "operators", usernames: ["ann"] }},
      {{ id: "viewers", usernames: ["vic"] }},
    ],
    policies: [
      {{ rules: ["command"], subjects: ["operators"] }},
      {{ rules: ["watch", "see-commands"], subjects: ["viewers"] }},
    ],
  }},
}}"#,
        dict = dictionary.display()
    )
}

fn client_config(user: &str, password: &str) -> String {
    format!(
        r#"{{ mode: "peer", transport: {{ auth: {{ usrpwd: {{ user: "{user}", password: "{password}" }} }} }} }}"#
    )
}

#[test]
fn only_operators_may_command_viewers_may_watch() {
    let dir = tempfile::tempdir().unwrap();
    let dictionary = dir.path().join("users.txt");
    std::fs::write(
        &dictionary,
        "ann:ann-secret\nvic:vic-secret\nr1:robot-secret\n",
    )
    .unwrap();
    let robot_cfg = dir.path().join("robot.json5");
    std::fs::write(&robot_cfg, robot_config(&dictionary)).unwrap();
    let endpoint = format!("unixsock-stream/{}", dir.path().join("z.sock").display());
    let robot = crate::RunningRobot::start(
        "r1",
        LinkConfig {
            listen: vec![endpoint.clone()],
            config_file: Some(robot_cfg),
            ..LinkConfig::default()
        },
        10.0,
    );
    let as_user = |user: &str, password: &str| {
        let cfg = dir.path().join(format!("{user}.json5"));
        std::fs::write(&cfg, client_config(user, password)).unwrap();
        Operator::connect(
            &LinkConfig {
                connect: vec![endpoint.clone()],
                config_file: Some(cfg),
                ..LinkConfig::default()
            },
            user,
        )
    };
    let mut ann = as_user("ann", "ann-secret").unwrap();
    let mut vic = as_user("vic", "vic-secret").unwrap();
    // The viewer watches the robot...
    assert!(vic.state("r1", Duration::from_secs(3)).is_ok());
    // ...but none of its commands reaches it: no reply, nothing done.
    for command in [
        Command::Status,
        Command::MoveRelative {
            dx_m: 0.5,
            dy_m: 0.0,
            dtheta_deg: 0.0,
        },
        Command::Stop,
    ] {
        let err = vic.send("r1", command, 2.0, None);
        assert!(err.is_err(), "a viewer's command got through: {err:?}");
    }
    let state = ann.state("r1", Duration::from_secs(3)).unwrap();
    assert_eq!(state["task"][1], "wait_for_operator", "{state}");
    // The operator commands.
    let r = ann.send("r1", Command::Status, 10.0, None).unwrap();
    assert_eq!(r.ack.reply, Reply::Done);
    // A wrong password joins nothing: either the session is refused, or
    // it reaches no robot.
    if let Ok(mut intruder) = as_user("ann", "guess") {
        assert!(intruder.send("r1", Command::Status, 2.0, None).is_err());
    }
    // The robot knows who tried: every refusal of the viewer's commands is
    // logged and kept, naming the viewer.
    let run = robot.stop();
    let refused: Vec<_> = run
        .denials
        .iter()
        .filter(|d| d.key == "stucco/r1/cmd" && d.action.starts_with("Query"))
        .collect();
    assert!(!refused.is_empty(), "no refusal logged: {:?}", run.denials);
    assert!(
        refused.iter().all(|d| d.subject.contains("Username(vic)")),
        "{refused:?}"
    );
    // Nothing of the operator's was refused.
    assert!(
        run.denials
            .iter()
            .all(|d| !d.subject.contains("Username(ann)")),
        "{:?}",
        run.denials
    );
}
