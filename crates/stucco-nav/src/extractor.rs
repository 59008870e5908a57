//! The interface every line extractor implements, so extractors can be
//! swapped and compared on the same scans.

use crate::points::ScanPoints;
use crate::wall::Wall;

/// Finds walls (straight lines) in the points of one scan.
pub trait WallExtractor {
    /// A short name for reports (`"rwht"`, `"ransac"`).
    fn name(&self) -> &'static str;

    /// The walls in `points`, strongest first.
    fn extract(&mut self, points: &ScanPoints) -> Vec<Wall>;
}
