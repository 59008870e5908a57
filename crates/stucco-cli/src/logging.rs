//! The process's log: human-readable lines on standard error, filtered by
//! `RUST_LOG` (default: stucco's notices, zenoh's errors and everyone
//! else's warnings), and
//! zenoh's access-control decisions read for the robot's audit.

use std::io::IsTerminal;
use tracing_subscriber::EnvFilter;
use tracing_subscriber::layer::SubscriberExt;
use tracing_subscriber::util::SubscriberInitExt;

/// What is logged when `RUST_LOG` is not set.
const DEFAULT_FILTER: &str = "warn,zenoh=error,stucco_cli=info,stucco_link=info";

/// Installs the process's log once; later calls (and a subscriber already
/// installed by someone else) leave it as it is.
pub fn init_logging() {
    let filter =
        EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(DEFAULT_FILTER));
    let fmt = tracing_subscriber::fmt::layer()
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .with_target(false);
    let _ = tracing_subscriber::registry()
        .with(tracing_subscriber::Layer::with_filter(fmt, filter))
        .with(stucco_link::audit::layer())
        .try_init();
}
