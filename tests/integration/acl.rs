//! Who may command: zenoh's own authentication (user/password, or TLS
//! certificates with mutual authentication) and access control in the
//! robot's embedded peer. An operator may command and watch; a viewer may
//! watch, its commands never reach the executive and the robot logs who
//! tried; an outsider joins nothing.

use std::path::{Path, PathBuf};
use std::time::Duration;
use stucco_cli::{LinkConfig, Operator};
use stucco_core::{Command, Reply};

/// Longest wait for a robot's state to reach an operator.
const STATE_WAIT: Duration = Duration::from_secs(10);

/// An example configuration shipped in `crates/stucco-link/config/`, with
/// each `(from, to)` replaced (every `from` must be there: the test runs
/// the file as users get it).
fn shipped(file: &str, replace: &[(&str, &str)]) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../crates/stucco-link/config")
        .join(file);
    let mut text = std::fs::read_to_string(&path).unwrap();
    for (from, to) in replace {
        assert!(text.contains(from), "{file} has no {from}");
        text = text.replace(from, to);
    }
    text
}

/// How the peers of one scenario join.
struct Site<'a> {
    dir: &'a Path,
    /// The robot's name (one per test: the tests share a process).
    name: &'a str,
    /// The robot's configuration file.
    robot: PathBuf,
    listen: String,
    connect: String,
    /// The zenoh configuration (JSON5) of a peer with these credentials.
    peer: &'a dyn Fn(&str) -> String,
    /// How zenoh names user `ann`'s or `vic`'s subject, e.g. `Username(vic)`.
    subject: &'a dyn Fn(&str) -> String,
    /// What the robot's log says of an outsider refused at joining.
    refused_at_joining: &'a str,
}

impl Site<'_> {
    fn join(&self, credentials: &str, identity: &str) -> anyhow::Result<Operator> {
        let cfg = self
            .dir
            .join(format!("{}.json5", credentials.replace([':', '/'], "_")));
        std::fs::write(&cfg, (self.peer)(credentials)).unwrap();
        let link = LinkConfig {
            connect: vec![self.connect.clone()],
            config_file: Some(cfg),
            ..LinkConfig::default()
        };
        Operator::connect(&link, identity)
    }

    /// The operator (`ann`) commands, the viewer (`vic`) watches and is
    /// refused (and
    /// named in the robot's log), each of `outsiders` reaches nothing.
    fn check(&self, [operator, viewer]: [&str; 2], outsiders: &[&str]) {
        let name = self.name;
        let robot = crate::RunningRobot::start(
            name,
            LinkConfig {
                listen: vec![self.listen.clone()],
                config_file: Some(self.robot.clone()),
                ..LinkConfig::default()
            },
            10.0,
        );
        let mut ann = self.join(operator, "ann").unwrap();
        let mut vic = self.join(viewer, "vic").unwrap();
        // The viewer watches the robot...
        assert!(vic.state(name, STATE_WAIT).is_ok());
        // ...but none of its commands reaches it: no reply, nothing done.
        for command in [
            Command::Status,
            Command::MoveRelative {
                dx_m: 0.5,
                dy_m: 0.0,
                dtheta_deg: 0.0,
                landmark: None,
            },
            Command::Stop,
        ] {
            let err = vic.send(name, command, 2.0, None);
            assert!(err.is_err(), "a viewer's command got through: {err:?}");
        }
        // Waited for as long as a loaded machine may take to publish it
        // (it comes as soon as it is there; 3 s failed once in four full
        // runs on 2 cores): a liveness wait, not the link's latency, which
        // the link bench measures.
        let state = ann.state(name, STATE_WAIT).unwrap();
        assert_eq!(
            state.task.as_ref().map(|t| t.1.as_str()),
            Some("wait_for_operator"),
            "{state:?}"
        );
        // The operator commands.
        let r = ann.send(name, Command::Status, 10.0, None).unwrap();
        assert_eq!(r.ack.reply, Reply::Done);
        // Authenticated as ann, commanding as vic: zenoh lets ann query her
        // own key only, so nothing reaches the robot as vic's.
        let mut posing = self.join(operator, "vic").unwrap();
        let r = posing.send(name, Command::Stop, 2.0, None);
        assert!(r.is_err(), "ann commanded as vic: {r:?}");
        // An outsider joins nothing: either the session is refused, or it
        // reaches no robot.
        for credentials in outsiders {
            if let Ok(mut intruder) = self.join(credentials, "ann") {
                let r = intruder.send(name, Command::Status, 2.0, None);
                assert!(r.is_err(), "{credentials} got through: {r:?}");
            }
        }
        // The robot knows who tried: every refusal of the viewer's
        // commands is logged and kept, naming the viewer.
        let run = robot.stop();
        // And who was refused at joining (the tests share a process: each
        // robot hears every refusal, so each test looks for its own kind).
        let joins: Vec<_> = run
            .denials
            .iter()
            .filter(|d| d.action.starts_with("Join"))
            .collect();
        println!("refused at joining: {joins:?}");
        assert!(
            joins
                .iter()
                .any(|d| d.action.contains(self.refused_at_joining)),
            "no outsider's refusal logged: {:?}",
            run.denials
        );
        let refused: Vec<_> = run
            .denials
            .iter()
            .filter(|d| d.key == format!("stucco/{name}/cmd/vic") && d.action.starts_with("Query"))
            .collect();
        assert!(!refused.is_empty(), "no refusal logged: {:?}", run.denials);
        // Each refusal names who tried: the viewer, or ann posing as vic.
        let (vic, ann) = ((self.subject)("vic"), (self.subject)("ann"));
        assert!(
            refused.iter().any(|d| d.subject.contains(&vic)),
            "{refused:?}"
        );
        assert!(
            refused.iter().any(|d| d.subject.contains(&ann)),
            "ann posing as vic is not logged: {refused:?}"
        );
        // None of ann's commands as herself was refused (zenoh also logs
        // the rules it weighs for her on keys she never uses).
        let own = format!("stucco/{name}/cmd/ann");
        assert!(
            !run.denials
                .iter()
                .any(|d| d.subject.contains(&ann) && d.key == own),
            "{:?}",
            run.denials
        );
    }
}

#[test]
fn only_operators_may_command_viewers_may_watch() {
    let dir = tempfile::tempdir().unwrap();
    let dictionary = dir.path().join("users.txt");
    std::fs::write(
        &dictionary,
        "ann:change-me-too\nvic:vic-secret\nr1:change-me\n",
    )
    .unwrap();
    let robot = dir.path().join("robot.json5");
    let dict = dictionary.display().to_string();
    std::fs::write(
        &robot,
        shipped("robot.json5", &[("/etc/stucco/users.txt", &dict)]),
    )
    .unwrap();
    let endpoint = format!("unixsock-stream/{}", dir.path().join("z.sock").display());
    // Credentials are `user:password`.
    let peer = |credentials: &str| {
        let (user, password) = credentials.split_once(':').unwrap();
        shipped(
            "operator.json5",
            &[
                ("user: \"ann\"", &format!("user: \"{user}\"")),
                (
                    "password: \"change-me-too\"",
                    &format!("password: \"{password}\""),
                ),
            ],
        )
    };
    Site {
        dir: dir.path(),
        name: "r1",
        robot,
        listen: endpoint.clone(),
        connect: endpoint,
        peer: &peer,
        subject: &|user| format!("Username({user})"),
        refused_at_joining: "wrong password",
    }
    .check(["ann:change-me-too", "vic:vic-secret"], &["ann:guess"]);
}

/// A certificate authority and the certificates it signs, as PEM files.
struct Authority {
    issuer: rcgen::CertifiedIssuer<'static, rcgen::KeyPair>,
    dir: PathBuf,
}

impl Authority {
    fn new(dir: &Path, name: &str) -> Self {
        let mut params = rcgen::CertificateParams::new(Vec::<String>::new()).unwrap();
        params.is_ca = rcgen::IsCa::Ca(rcgen::BasicConstraints::Unconstrained);
        params
            .distinguished_name
            .push(rcgen::DnType::CommonName, name);
        let issuer =
            rcgen::CertifiedIssuer::self_signed(params, rcgen::KeyPair::generate().unwrap())
                .unwrap();
        let dir = dir.join(name);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("ca.pem"), issuer.pem()).unwrap();
        Authority { issuer, dir }
    }

    fn root(&self) -> PathBuf {
        self.dir.join("ca.pem")
    }

    /// A certificate with common name `cn` (valid for `localhost` and
    /// 127.0.0.1): its certificate and key files.
    fn sign(&self, cn: &str) -> (PathBuf, PathBuf) {
        let mut params =
            rcgen::CertificateParams::new(vec!["localhost".to_owned(), "127.0.0.1".to_owned()])
                .unwrap();
        params
            .distinguished_name
            .push(rcgen::DnType::CommonName, cn);
        let key = rcgen::KeyPair::generate().unwrap();
        let cert = params.signed_by(&key, &self.issuer).unwrap();
        let (c, k) = (
            self.dir.join(format!("{cn}.pem")),
            self.dir.join(format!("{cn}.key")),
        );
        std::fs::write(&c, cert.pem()).unwrap();
        std::fs::write(&k, key.serialize_pem()).unwrap();
        (c, k)
    }
}

/// A TCP port free a moment ago (TLS runs over TCP; never a fixed port).
fn free_port() -> u16 {
    let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    l.local_addr().unwrap().port()
}

#[test]
fn with_tls_certificates_only_operators_may_command() {
    let dir = tempfile::tempdir().unwrap();
    let site = Authority::new(dir.path(), "site-ca");
    let stranger = Authority::new(dir.path(), "stranger-ca");
    let root = site.root().display().to_string();
    let (cert, key) = site.sign("r2");
    let robot = dir.path().join("robot.json5");
    std::fs::write(
        &robot,
        shipped(
            "robot-tls.json5",
            &[
                ("/etc/stucco/tls/site-ca.pem", &root),
                ("/etc/stucco/tls/r1.pem", &cert.display().to_string()),
                ("/etc/stucco/tls/r1.key", &key.display().to_string()),
                // This test's robot is r2 (r1 is another test's, in the
                // same process).
                ("stucco/r1/", "stucco/r2/"),
            ],
        ),
    )
    .unwrap();
    // Credentials: a common name signed by the site's authority,
    // `stranger:CN` signed by another one, or none at all.
    let peer = |credentials: &str| {
        let (ca, cn) = match credentials.split_once(':') {
            Some((_, cn)) => (&stranger, cn),
            None => (&site, credentials),
        };
        let (cert, key) = ca.sign(cn);
        let (cert, key) = (cert.display().to_string(), key.display().to_string());
        let (cert_line, key_line) = if credentials == "no-certificate" {
            (String::new(), String::new())
        } else {
            (
                format!("connect_certificate: \"{cert}\","),
                format!("connect_private_key: \"{key}\","),
            )
        };
        shipped(
            "operator-tls.json5",
            &[
                ("/etc/stucco/tls/site-ca.pem", &root),
                (
                    "connect_certificate: \"/home/ann/.stucco/ann.pem\",",
                    &cert_line,
                ),
                (
                    "connect_private_key: \"/home/ann/.stucco/ann.key\",",
                    &key_line,
                ),
            ],
        )
    };
    let port = free_port();
    Site {
        dir: dir.path(),
        name: "r2",
        robot,
        listen: format!("tls/127.0.0.1:{port}"),
        connect: format!("tls/localhost:{port}"),
        peer: &peer,
        subject: &|cn| format!("CertCommonName({cn})"),
        refused_at_joining: "TLS",
    }
    .check(["ann", "vic"], &["stranger:ann", "no-certificate"]);
}
