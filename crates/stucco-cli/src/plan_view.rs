//! A floor plan drawn as SVG: wall segments, paths and marks, on square
//! axes in metres. Shared by `stucco walls` and `stucco replay`.

use std::path::Path;

use anyhow::Result;
use plotters::prelude::*;

/// A wall to draw: its two ends, m, and whether to draw it faint.
pub type PlanSegment = ((f64, f64), (f64, f64), bool);

/// A path to draw: its points and colour.
pub struct PlanPath<'a> {
    /// The points, m.
    pub points: &'a [(f64, f64)],
    /// Its colour.
    pub color: RGBColor,
}

/// Draws `segments` (black; grey when the flag is set), `paths` and
/// `marks` (red dots) into an SVG at `path`, the axes square around all of
/// them.
pub fn draw_plan(
    path: &Path,
    caption: &str,
    segments: &[PlanSegment],
    paths: &[PlanPath<'_>],
    marks: &[(f64, f64)],
) -> Result<()> {
    let xs = segments
        .iter()
        .flat_map(|s| [s.0.0, s.1.0])
        .chain(paths.iter().flat_map(|p| p.points.iter().map(|q| q.0)));
    let ys = segments
        .iter()
        .flat_map(|s| [s.0.1, s.1.1])
        .chain(paths.iter().flat_map(|p| p.points.iter().map(|q| q.1)));
    let span_of = |v: &mut dyn Iterator<Item = f64>| {
        v.filter(|x| x.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |m, x| {
                (m.0.min(x), m.1.max(x))
            })
    };
    let ((x0, x1), (y0, y1)) = (span_of(&mut { xs }), span_of(&mut { ys }));
    let (x0, x1, y0, y1) = if x0 <= x1 && y0 <= y1 {
        (x0, x1, y0, y1)
    } else {
        (0.0, 0.0, 0.0, 0.0)
    };
    let span = (x1 - x0).max(y1 - y0).max(1.0) + 2.0;
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let root = SVGBackend::new(path, (1000, 1000)).into_drawing_area();
    let err = |e: &dyn std::fmt::Display| anyhow::anyhow!("drawing {}: {e}", path.display());
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(40)
        .build_cartesian_2d(
            cx - span / 2.0..cx + span / 2.0,
            cy - span / 2.0..cy + span / 2.0,
        )
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .draw()
        .map_err(|e| err(&e))?;
    for p in paths {
        chart
            .draw_series(LineSeries::new(p.points.iter().copied(), p.color.mix(0.5)))
            .map_err(|e| err(&e))?;
    }
    chart
        .draw_series(segments.iter().map(|(a, b, faint)| {
            let color = if *faint {
                RGBColor(150, 150, 150)
            } else {
                BLACK
            };
            PathElement::new(vec![*a, *b], color.stroke_width(2))
        }))
        .map_err(|e| err(&e))?;
    chart
        .draw_series(marks.iter().map(|d| Circle::new(*d, 4, RED.filled())))
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
