//! Acceptance tests live in `integration/`.
