//! The log–log plot of a study: error against mesh size h, one series per
//! method and norm (colour = method, marker = norm), reference slopes for
//! orders 1 and 2, and a legend beside the chart.
//!
//! Text in PNGs is rendered by `ab_glyph` from a subset of DejaVu Sans
//! embedded in the binary (`solver/assets/`), so plotting needs no system
//! font library; SVGs name the font family and leave rendering to the
//! viewer.

use super::{Norm, Refinement, StudyResult};
use image::ImageEncoder;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::sync::OnceLock;

/// The embedded font (DejaVu Sans subset; licence next to it).
static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans-subset.ttf");

/// The family name every text of the plot asks for.
const FAMILY: &str = "sans-serif";

/// Why a plot could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The font embedded in the binary was refused by the renderer (a
    /// broken build, not bad input).
    #[error("the embedded plot font could not be loaded")]
    Font,
    /// The plotting library failed, e.g. on a size too small for the
    /// chart; the message is its own.
    #[error("drawing the plot: {0}")]
    Draw(String),
    /// No error is positive and finite, so a logarithmic axis has nothing
    /// to show.
    #[error("nothing to plot: no level has a positive error")]
    Empty,
}

/// Image formats of a study's plot.
///
/// ```
/// use hasse_solver::study::{PlotFormat, PlotOptions, Refinement, StudyResult, StudyRow};
/// let row = |level: usize, h: f64, l2: f64| StudyRow {
///     method: "fe".into(), level, resolution: vec![], h, cells: 0, unknowns: 0,
///     l2, max: l2, gradient_l2: None, flux: None, mesh_seconds: 0.0, solve_seconds: 0.0,
/// };
/// let result = StudyResult {
///     case: "demo.toml".into(), title: None, refinement: Refinement::Uniform, levels: 2,
///     methods: vec!["fe".into()], rows: vec![row(0, 0.2, 4e-2), row(1, 0.1, 1e-2)],
/// };
/// let options = PlotOptions { width: 320, height: 200 };
/// let bytes = |format| match format {
///     PlotFormat::Png => result.png(options).unwrap(),
///     PlotFormat::Svg => result.svg(options).unwrap().into_bytes(),
/// };
/// // The PNG signature, and an XML document with an <svg> element.
/// assert_eq!(&bytes(PlotFormat::Png)[..4], b"\x89PNG");
/// assert!(String::from_utf8(bytes(PlotFormat::Svg)).unwrap().contains("<svg"));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlotFormat {
    /// A raster image ([`StudyResult::png`]), text drawn with the
    /// embedded font.
    Png,
    /// A vector image ([`StudyResult::svg`]); the viewer renders the
    /// text.
    Svg,
}

/// Size of the plot in pixels (SVG: user units).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlotOptions {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Default for PlotOptions {
    /// 960 × 600.
    fn default() -> Self {
        Self {
            width: 960,
            height: 600,
        }
    }
}

fn register_font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = REGISTERED
        .get_or_init(|| plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if *ok {
        Ok(())
    } else {
        Err(PlotError::Font)
    }
}

fn draw_error<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> PlotError {
    PlotError::Draw(e.to_string())
}

/// Colour of the i-th method: a colour-blind safe palette (Okabe–Ito).
fn colour(i: usize) -> RGBColor {
    const PALETTE: [RGBColor; 7] = [
        RGBColor(0, 114, 178),
        RGBColor(213, 94, 0),
        RGBColor(0, 158, 115),
        RGBColor(204, 121, 167),
        RGBColor(230, 159, 0),
        RGBColor(86, 180, 233),
        RGBColor(0, 0, 0),
    ];
    PALETTE[i % PALETTE.len()]
}

/// One plotted series.
struct Series {
    label: String,
    colour: RGBColor,
    norm: Norm,
    points: Vec<(f64, f64)>,
}

/// A marker of the norm at `at`, in backend coordinates or chart
/// coordinates alike.
fn marker<C: Clone + 'static, DB: DrawingBackend>(
    area: &DrawingArea<DB, impl plotters::coord::CoordTranslate<From = C>>,
    norm: Norm,
    at: C,
    colour: RGBColor,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let r = 4;
    match norm {
        Norm::L2 => area.draw(&Circle::new(at, r, colour.filled())),
        Norm::Max => area.draw(&TriangleMarker::new(at, r + 1, colour.filled())),
        Norm::GradientL2 => area.draw(&Circle::new(at, r, colour.stroke_width(2))),
        Norm::Flux => area.draw(&Cross::new(at, r, colour.stroke_width(2))),
    }
    .map_err(draw_error)
}

/// An integer as Unicode superscript digits (with a superscript minus).
fn superscript(k: i32) -> String {
    const DIGITS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut out = String::new();
    if k < 0 {
        out.push('⁻');
    }
    for c in k.unsigned_abs().to_string().chars() {
        out.push(DIGITS[c as usize - '0' as usize]);
    }
    out
}

/// Axis labels at 1, 2 and 5 × 10ᵏ only, written as a paper would (10⁻²,
/// 2·10⁻²): plotters' log axes put key points at every integer mantissa,
/// and their labels collide inside one decade.
fn log_label(v: &f64) -> String {
    if !(*v > 0.0 && v.is_finite()) {
        return String::new();
    }
    let exponent = v.log10().floor();
    let mantissa = v / 10f64.powf(exponent);
    let rounded = mantissa.round();
    let (mantissa, exponent) = if (mantissa - 10.0).abs() < 1e-6 {
        (1.0, exponent + 1.0)
    } else if (mantissa - rounded).abs() < 1e-6 && [1.0, 2.0, 5.0].contains(&rounded) {
        (rounded, exponent)
    } else {
        return String::new();
    };
    let power = format!("10{}", superscript(exponent as i32));
    if mantissa == 1.0 {
        power
    } else {
        format!("{mantissa}·{power}")
    }
}

/// How a reference slope is drawn: order 1 dotted, order 2 dashed, so the
/// two stay apart in print without colour.
fn reference_dashes(order: f64) -> (u32, u32) {
    if order < 1.5 {
        (2, 4)
    } else {
        (8, 4)
    }
}

impl StudyResult {
    /// The plot's title: the methods compared, after the case's title when
    /// the study keeps it (its own method), else after the case file's name.
    fn caption(&self) -> String {
        let methods = self.methods.join(", ");
        match &self.title {
            Some(t) => format!("{t} ({methods})"),
            None => {
                let name = std::path::Path::new(&self.case)
                    .file_name()
                    .map_or(self.case.clone(), |n| n.to_string_lossy().into_owned());
                format!("{methods} on {name}")
            }
        }
    }

    fn series(&self) -> Vec<Series> {
        let mut out = Vec::new();
        for (i, method) in self.methods.iter().enumerate() {
            for norm in self.norms(method) {
                let points: Vec<(f64, f64)> = self
                    .method_rows(method)
                    .filter_map(|r| r.error(norm).map(|e| (r.h, e)))
                    .filter(|&(h, e)| h > 0.0 && e > 0.0 && h.is_finite() && e.is_finite())
                    .collect();
                if !points.is_empty() {
                    out.push(Series {
                        label: format!("{method} · {}", norm.label()),
                        colour: colour(i),
                        norm,
                        points,
                    });
                }
            }
        }
        out
    }

    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<(), PlotError>
    where
        DB::ErrorType: 'static,
    {
        let series = self.series();
        if series.is_empty() {
            return Err(PlotError::Empty);
        }
        let points = || series.iter().flat_map(|s| s.points.iter().copied());
        let (h_lo, h_hi) =
            points().fold((f64::MAX, f64::MIN), |(a, b), (h, _)| (a.min(h), b.max(h)));
        // Reference slopes start below every series at the coarsest h, so
        // they never hide data, and fall as h^1 and h^2 from there.
        let coarsest_min = points()
            .filter(|&(h, _)| h == h_hi)
            .map(|(_, e)| e)
            .fold(f64::MAX, f64::min);
        let anchor = coarsest_min * 0.4;
        let reference = |p: f64| -> Vec<(f64, f64)> {
            [h_hi, h_lo]
                .iter()
                .map(|&h| (h, anchor * (h / h_hi).powf(p)))
                .collect()
        };
        let references = [(1.0, reference(1.0)), (2.0, reference(2.0))];
        let (e_lo, e_hi) = points()
            .chain(references.iter().flat_map(|(_, r)| r.iter().copied()))
            .fold((f64::MAX, f64::MIN), |(a, b), (_, e)| (a.min(e), b.max(e)));
        // Half a decade of room around the data on the error axis, a tenth
        // of the span on the h axis (a single level still gets a range).
        let (x_lo, x_hi) = (h_lo / 1.25, h_hi * 1.25);
        let (y_lo, y_hi) = (e_lo / 3.0, e_hi * 3.0);

        root.fill(&WHITE).map_err(draw_error)?;
        let (width, _) = root.dim_in_pixel();
        let legend_width = 230.min(width / 3);
        let (chart_area, legend_area) = root.split_horizontally(width - legend_width);
        let title = self.caption();
        let mut chart = ChartBuilder::on(&chart_area)
            .caption(title, (FAMILY, 18))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(78)
            .build_cartesian_2d((x_lo..x_hi).log_scale(), (y_lo..y_hi).log_scale())
            .map_err(draw_error)?;
        chart
            .configure_mesh()
            .x_desc(match self.refinement {
                Refinement::Uniform | Refinement::Split => "mesh size h (largest cell diameter)",
                Refinement::Time => "time step Δt",
            })
            .y_desc("error")
            .label_style((FAMILY, 13))
            .axis_desc_style((FAMILY, 15))
            .max_light_lines(0)
            .x_label_formatter(&log_label)
            .y_label_formatter(&log_label)
            .draw()
            .map_err(draw_error)?;
        let grey = RGBColor(110, 110, 110);
        for (p, line) in &references {
            let (dash, gap) = reference_dashes(*p);
            chart
                .draw_series(DashedLineSeries::new(
                    line.iter().copied(),
                    dash,
                    gap,
                    grey.stroke_width(1),
                ))
                .map_err(draw_error)?;
            // The slope's name at its fine end, where the lines are apart.
            if let Some(&(h, e)) = line.last() {
                chart
                    .draw_series(std::iter::once(Text::new(
                        format!("h{}", superscript(*p as i32)),
                        (h, e),
                        (FAMILY, 13).into_font().color(&grey),
                    )))
                    .map_err(draw_error)?;
            }
        }
        for s in &series {
            chart
                .draw_series(LineSeries::new(
                    s.points.iter().copied(),
                    s.colour.stroke_width(2),
                ))
                .map_err(draw_error)?;
            let area = chart.plotting_area();
            for &p in &s.points {
                marker(area, s.norm, p, s.colour)?;
            }
        }

        // The legend: one entry per series, then the reference slopes.
        let font = (FAMILY, 13).into_font().color(&BLACK);
        let row = 20;
        let mut y = 40;
        for s in &series {
            legend_area
                .draw(&PathElement::new(
                    vec![(8, y), (40, y)],
                    s.colour.stroke_width(2),
                ))
                .map_err(draw_error)?;
            marker(&legend_area, s.norm, (24, y), s.colour)?;
            legend_area
                .draw(&Text::new(s.label.clone(), (48, y - 7), font.clone()))
                .map_err(draw_error)?;
            y += row;
        }
        for (p, _) in &references {
            let (dash, gap) = reference_dashes(*p);
            let mut x = 8;
            while x < 40 {
                legend_area
                    .draw(&PathElement::new(
                        vec![(x, y), ((x + dash as i32).min(40), y)],
                        grey.stroke_width(1),
                    ))
                    .map_err(draw_error)?;
                x += (dash + gap) as i32;
            }
            legend_area
                .draw(&Text::new(
                    format!("reference slope {p:.0} (h{})", superscript(*p as i32)),
                    (48, y - 7),
                    font.clone(),
                ))
                .map_err(draw_error)?;
            y += row;
        }
        root.present().map_err(draw_error)?;
        Ok(())
    }

    /// The plot as an SVG document.
    ///
    /// ```
    /// use hasse_solver::study::{PlotOptions, Refinement, StudyResult, StudyRow};
    /// let row = |level: usize, h: f64, l2: f64| StudyRow {
    ///     method: "fd".into(), level, resolution: vec![], h, cells: 0, unknowns: 0,
    ///     l2, max: l2, gradient_l2: None, flux: None, mesh_seconds: 0.0, solve_seconds: 0.0,
    /// };
    /// let result = StudyResult {
    ///     case: "demo.toml".into(), title: None, refinement: Refinement::Uniform, levels: 2,
    ///     methods: vec!["fd".into()], rows: vec![row(0, 0.2, 4e-2), row(1, 0.1, 1e-2)],
    /// };
    /// let svg = result.svg(PlotOptions { width: 640, height: 400 }).unwrap();
    /// assert!(svg.contains(r#"width="640""#) && svg.contains("fd · L²"));
    /// ```
    pub fn svg(&self, options: PlotOptions) -> Result<String, PlotError> {
        register_font()?;
        let mut text = String::new();
        {
            let root = SVGBackend::with_string(&mut text, (options.width, options.height))
                .into_drawing_area();
            self.draw(root)?;
        }
        Ok(text)
    }

    /// The plot as a PNG image (the bytes of the file).
    ///
    /// ```
    /// use hasse_solver::study::{PlotOptions, Refinement, StudyResult, StudyRow};
    /// let row = |level: usize, h: f64, l2: f64| StudyRow {
    ///     method: "fe".into(), level, resolution: vec![], h, cells: 0, unknowns: 0,
    ///     l2, max: l2, gradient_l2: None, flux: None, mesh_seconds: 0.0, solve_seconds: 0.0,
    /// };
    /// let result = StudyResult {
    ///     case: "demo.toml".into(), title: Some("demo".into()), refinement: Refinement::Uniform,
    ///     levels: 2, methods: vec!["fe".into()], rows: vec![row(0, 0.2, 4e-2), row(1, 0.1, 1e-2)],
    /// };
    /// let png = result.png(PlotOptions { width: 320, height: 200 }).unwrap();
    /// assert_eq!(&png[1..4], b"PNG");
    /// ```
    pub fn png(&self, options: PlotOptions) -> Result<Vec<u8>, PlotError> {
        register_font()?;
        let (width, height) = (options.width, options.height);
        let mut rgb = vec![0u8; 3 * width as usize * height as usize];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
            self.draw(root)?;
        }
        let mut bytes = Vec::new();
        image::codecs::png::PngEncoder::new(&mut bytes)
            .write_image(&rgb, width, height, image::ColorType::Rgb8)
            .map_err(|e| PlotError::Draw(e.to_string()))?;
        Ok(bytes)
    }
}
