//! The plots of `stucco study`: one per axis, as the sensor-precision
//! paper's Fig. 5–8 — the relative pose error of each setting with its
//! spread, the odometry alone for reference — drawn once as SVG and
//! rasterised from that SVG to PNG.

use std::path::Path;

use anyhow::{Context, Result, anyhow};
use plotters::coord::Shift;
use plotters::prelude::*;
use resvg::{tiny_skia, usvg};
use stucco_nav::Rpe;

/// One setting of an axis.
#[derive(Clone, Copy, Debug)]
pub struct AxisPoint {
    /// The setting.
    pub x: f64,
    /// The filter's error over its runs.
    pub rpe: Rpe,
    /// The odometry's, on the same drives.
    pub odom: Rpe,
}

const SIZE: (u32, u32) = (1200, 480);

/// Draws `points` into `STEM.svg` and `STEM.png`: translational error on
/// the left, rotational on the right, each mean with a bar of ± one
/// standard deviation over the pairs, on a log scale (the settings too
/// when `log_x`).
pub fn draw_axis(
    stem: &Path,
    title: &str,
    x_label: &str,
    log_x: bool,
    points: &[AxisPoint],
) -> Result<()> {
    let points: Vec<AxisPoint> = points
        .iter()
        .map(|p| AxisPoint {
            x: if log_x { p.x.ln() } else { p.x },
            ..*p
        })
        .collect();
    let points = &points[..];
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        let err = |e: &dyn std::fmt::Display| anyhow!("drawing {}: {e}", stem.display());
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let root = root
            .titled(title, ("sans-serif", 20))
            .map_err(|e| err(&e))?;
        let (left, right) = root.split_horizontally(SIZE.0 / 2);
        panel(
            &left,
            (x_label, log_x),
            "translational RPE, m",
            points,
            |r| (r.trans_mean_m, r.trans_std_m),
        )
        .map_err(|e| err(&e))?;
        panel(
            &right,
            (x_label, log_x),
            "rotational RPE, rad",
            points,
            |r| (r.rot_mean_rad, r.rot_std_rad),
        )
        .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    let svg_path = stem.with_extension("svg");
    std::fs::write(&svg_path, &svg).with_context(|| format!("writing {}", svg_path.display()))?;
    rasterise(&svg, &stem.with_extension("png"))
}

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

fn panel(
    area: &Area<'_>,
    (x_label, log_x): (&str, bool),
    y_label: &str,
    points: &[AxisPoint],
    of: impl Fn(&Rpe) -> (f64, f64),
) -> Result<(), DrawingAreaErrorKind<std::io::Error>> {
    let xs = points.iter().map(|p| p.x);
    let (x0, x1) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |m, x| {
        (m.0.min(x), m.1.max(x))
    });
    let pad = ((x1 - x0) * 0.05).max(1e-3);
    let values = points
        .iter()
        .flat_map(|p| {
            let (m, s) = of(&p.rpe);
            [m + s, m, of(&p.odom).0]
        })
        .filter(|v| v.is_finite() && *v > 0.0);
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |m, v| (m.0.min(v), m.1.max(v)));
    let (lo, hi) = if lo <= hi {
        (lo / 2.0, hi * 2.0)
    } else {
        (1e-4, 1.0)
    };
    let mut chart = ChartBuilder::on(area)
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x0 - pad..x1 + pad, (lo..hi).log_scale())?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .x_label_formatter(&|v| {
            if log_x {
                format!("{:.2}", v.exp())
            } else {
                format!("{v}")
            }
        })
        .y_desc(y_label)
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()?;
    let floor = lo;
    chart.draw_series(points.iter().map(|p| {
        let (m, s) = of(&p.rpe);
        ErrorBar::new_vertical(p.x, (m - s).max(floor), m, m + s, BLUE.filled(), 10)
    }))?;
    chart
        .draw_series(LineSeries::new(
            points.iter().map(|p| (p.x, of(&p.rpe).0)),
            BLUE.stroke_width(2),
        ))?
        .label("wall-map EKF (mean ± std)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.stroke_width(2)));
    chart
        .draw_series(LineSeries::new(
            points.iter().map(|p| (p.x, of(&p.odom).0)),
            RED.stroke_width(1),
        ))?
        .label("odometry alone (mean)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// `svg` rendered to a PNG at `path`, with the system's fonts.
pub fn rasterise(svg: &str, path: &Path) -> Result<()> {
    let mut options = usvg::Options::default();
    let fonts = options.fontdb_mut();
    fonts.load_system_fonts();
    // The plots ask for "sans-serif"; fontdb maps it to Arial, which a
    // Linux machine seldom has: take the first sans face it has instead.
    let sans = ["DejaVu Sans", "Liberation Sans", "Noto Sans", "FreeSans"]
        .into_iter()
        .find(|name| {
            fonts
                .faces()
                .any(|f| f.families.iter().any(|(family, _)| family == name))
        })
        .map(str::to_owned)
        .or_else(|| {
            fonts
                .faces()
                .next()
                .and_then(|f| f.families.first().map(|(family, _)| family.clone()))
        });
    if let Some(family) = sans {
        fonts.set_sans_serif_family(family);
    }
    let tree = usvg::Tree::from_str(svg, &options)
        .map_err(|e| anyhow!("reading back the SVG for {}: {e}", path.display()))?;
    let size = tree.size().to_int_size();
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height())
        .ok_or_else(|| anyhow!("{}: an empty image", path.display()))?;
    pixmap.fill(tiny_skia::Color::WHITE);
    resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
    pixmap
        .save_png(path)
        .map_err(|e| anyhow!("writing {}: {e}", path.display()))
}
