//! `track motion`: robust parametric motion between two frames (Odobez et al. 2003 §4.2).

use std::path::{Path, PathBuf};
use std::time::Instant;

use motion_est::{
    MaskView, ModelSpec, MotionEstimate, MotionEstimator, MotionModel, Region, Settings,
};
use vision_core::GreyImage;

use crate::{AppError, Result};

/// The displacement model on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ModelArg {
    /// Translation (2 parameters).
    Translation,
    /// Translation and isotropic scale (3 parameters).
    Scale,
    /// Affine, Odobez Eq. 13 (6 parameters).
    Affine,
}

impl From<ModelArg> for MotionModel {
    fn from(m: ModelArg) -> Self {
        match m {
            ModelArg::Translation => MotionModel::Translation,
            ModelArg::Scale => MotionModel::Scale,
            ModelArg::Affine => MotionModel::Affine,
        }
    }
}

/// Arguments of `track motion`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:\n  \
    track motion a.png b.png --json\n  \
    track motion girl_mil/img/0001.png girl_mil/img/0002.png --roi 128,46,104,127 --origin 180,110\n  \
    track motion a.png b.png --mask head.png --model scale --offset\n\n\
On real footage a region that holds no single affine motion (a head turning, a hand crossing it)\n\
is flagged unreliable and nothing is printed (exit 1): choose a region that moves as one.")]
pub struct Args {
    /// The first frame (any grey or colour image; colour is converted to grey).
    pub frame0: PathBuf,
    /// The second frame, the same size.
    pub frame1: PathBuf,
    /// Support region as a rectangle x,y,w,h (pixels); default the whole frame.
    #[arg(long, value_name = "x,y,w,h", conflicts_with = "mask")]
    pub roi: Option<String>,
    /// Support region as a mask image the size of the frames: grey level / 255 is the weight.
    #[arg(long, value_name = "MASK.png")]
    pub mask: Option<PathBuf>,
    /// Displacement model.
    #[arg(long, value_enum, default_value = "affine")]
    pub model: ModelArg,
    /// Also estimate a global intensity offset.
    #[arg(long)]
    pub offset: bool,
    /// Origin x,y of the model's coordinates; default the region's centre. At most one frame
    /// width (height) outside the frames.
    #[arg(long, value_name = "x,y")]
    pub origin: Option<String>,
    /// Convergence tolerance at full resolution: the largest change of the region's corners in
    /// one iteration, in pixels, in (0, 1]. IRLS converges linearly, and on real 8-bit frames
    /// its steps level off around a hundredth of a pixel, so a tolerance far below that is
    /// rarely met; the final scale and covariance are evaluated at the estimate whatever the
    /// tolerance. motion-est's tests check 0.1 against the same accuracy and calibration bounds
    /// as the library's default 5e-4.
    #[arg(long, value_name = "PX", default_value_t = DEFAULT_TOLERANCE, value_parser = parse_tolerance)]
    pub tolerance: f64,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `--tolerance`'s default, pixels: that of motion-est's tracking settings
/// (`Settings::tracking`), with the default number of iterations.
pub const DEFAULT_TOLERANCE: f64 = 0.1;

/// Parses `--tolerance`: a number of pixels in (0, 1].
fn parse_tolerance(s: &str) -> std::result::Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s} is not a number of pixels"))?;
    if !(v.is_finite() && v > 0.0 && v <= 1.0) {
        return Err(format!(
            "{s} is out of range: give a number of pixels in (0, 1]"
        ));
    }
    Ok(v)
}

/// The estimator's settings for `track motion`: the library's defaults with both convergence
/// tolerances set to `tolerance` (see [`Args::tolerance`]).
pub fn settings(tolerance: f64) -> Settings {
    Settings {
        tolerance,
        coarse_tolerance: tolerance.max(Settings::default().coarse_tolerance),
        ..Settings::default()
    }
}

/// Runs `track motion`.
///
/// # Errors
/// [`AppError::InvalidSetting`] for a malformed `--roi` / `--origin`, a `--roi` outside the
/// frames or too small, an `--origin` too far from them; [`AppError::BadInput`] for unreadable or
/// mismatched images; [`AppError::Computation`] (exit 1) when the estimate fails (for example a
/// textureless region) or must not be reported ([`assess`]): with `--json` a failure object is
/// printed first.
pub fn run(args: &Args) -> Result<()> {
    let roi = args
        .roi
        .as_deref()
        .map(|s| parse_floats::<4>("--roi", s))
        .transpose()?;
    let origin = args
        .origin
        .as_deref()
        .map(|s| parse_floats::<2>("--origin", s))
        .transpose()?;
    let (w, h, f0) = load_grey(&args.frame0)?;
    let (w1, h1, f1) = load_grey(&args.frame1)?;
    if (w1, h1) != (w, h) {
        return Err(AppError::input(
            &args.frame1,
            format!("size {w1}×{h1} differs from the first frame's {w}×{h}"),
        ));
    }
    let mask = match &args.mask {
        Some(path) => {
            let (mw, mh, m) = load_grey(path)?;
            if (mw, mh) != (w, h) {
                return Err(AppError::input(
                    path,
                    format!("mask size {mw}×{mh} differs from the frames' {w}×{h}"),
                ));
            }
            Some(
                m.into_iter()
                    .map(|v| (v / 255.0).clamp(0.0, 1.0))
                    .collect::<Vec<f32>>(),
            )
        }
        None => None,
    };
    if let Some(o) = origin {
        check_origin(o, w, h)?;
    }
    let region = match (&roi, &mask) {
        (Some(r), _) => {
            check_roi(r, w, h)?;
            Region::Rect {
                x: r[0],
                y: r[1],
                width: r[2],
                height: r[3],
            }
        }
        (None, Some(m)) => Region::Mask(
            MaskView::new(w, h, m).map_err(|e| AppError::setting("--mask", e.to_string()))?,
        ),
        (None, None) => Region::Full,
    };
    let spec = ModelSpec::new(args.model.into(), args.offset);
    let estimator = MotionEstimator::new(settings(args.tolerance))
        .map_err(|e| AppError::setting("--tolerance", e.to_string()))?;
    let view0 =
        GreyImage::new(w, h, &f0).map_err(|e| AppError::input(&args.frame0, e.to_string()))?;
    let view1 =
        GreyImage::new(w, h, &f1).map_err(|e| AppError::input(&args.frame1, e.to_string()))?;
    let start = Instant::now();
    let est = estimator
        .estimate_images(view0, view1, &region, spec, origin)
        // An unreliable estimate is motion-est's error carrying the estimate: taken back here so
        // that `assess` reports why, and the JSON failure object has its diagnostics.
        .or_else(motion_est::Error::into_unreliable)
        .map_err(|e| match e {
            motion_est::Error::InvalidSetting { name, .. } => {
                AppError::setting(name, e.to_string())
            }
            // A region too small for the model is the region's fault: the option that gave it.
            motion_est::Error::RegionTooSmall { .. } if roi.is_some() => {
                AppError::setting("--roi", e.to_string())
            }
            motion_est::Error::RegionTooSmall { .. } if mask.is_some() => {
                AppError::setting("--mask", e.to_string())
            }
            other => {
                // No estimate at all (textureless frames): with --json still the documented
                // failure object, so that a script reading standard output learns why.
                let e = AppError::computation("motion estimation", other);
                if args.json
                    && let Err(print) = crate::output::println_stdout(&failure_json_without(
                        spec,
                        origin,
                        &e.to_string(),
                    ))
                {
                    return print;
                }
                e
            }
        })?;
    let millis = start.elapsed().as_secs_f64() * 1e3;
    if let Err(reason) = assess(&est) {
        // A failed estimate is never printed as a result: JSON gets an explicit failure status
        // without parameters or covariance, text only the error line; the exit code is 1.
        if args.json {
            crate::output::println_stdout(&failure_json(&est, &reason, millis))?;
        }
        return Err(AppError::computation(
            "motion estimation failed",
            format!("{reason}; no motion is reported"),
        ));
    }
    let out = if args.json {
        to_json(&est, millis)
    } else {
        to_text(&est, millis)
    };
    crate::output::println_stdout(&out)
}

/// Checks that `--roi` has a positive size and overlaps the `w`×`h` frames.
///
/// # Errors
/// [`AppError::InvalidSetting`] naming `--roi`.
fn check_roi(r: &[f64; 4], w: usize, h: usize) -> Result<()> {
    if r[2] <= 0.0 || r[3] <= 0.0 {
        return Err(AppError::setting(
            "--roi",
            "width and height must be positive",
        ));
    }
    let (wf, hf) = (w as f64, h as f64);
    if r[0] >= wf || r[1] >= hf || r[0] + r[2] <= 0.0 || r[1] + r[3] <= 0.0 {
        return Err(AppError::setting(
            "--roi",
            format!(
                "the rectangle {} lies outside the {w}×{h} frames",
                r.map(crate::groundtruth::fmt_num).join(",")
            ),
        ));
    }
    Ok(())
}

/// How far outside the frames `--origin` may lie, in frame widths and heights. The model's
/// coordinates are taken relative to the origin; an origin far from the pixels makes the
/// affine normal equations so ill-conditioned that the covariance loses its meaning (an origin
/// at (10⁶, 10⁶) gave a negative variance).
pub const ORIGIN_REACH: f64 = 1.0;

/// Checks that `--origin` lies within [`ORIGIN_REACH`] frame sizes of the `w`×`h` frames.
///
/// # Errors
/// [`AppError::InvalidSetting`] naming `--origin` and the range allowed.
fn check_origin(o: [f64; 2], w: usize, h: usize) -> Result<()> {
    let (wf, hf) = (w as f64, h as f64);
    let (x0, x1) = (-ORIGIN_REACH * wf, (1.0 + ORIGIN_REACH) * wf);
    let (y0, y1) = (-ORIGIN_REACH * hf, (1.0 + ORIGIN_REACH) * hf);
    if !(x0..=x1).contains(&o[0]) || !(y0..=y1).contains(&o[1]) {
        return Err(AppError::setting(
            "--origin",
            format!(
                "{},{} is too far from the {w}×{h} frames: x must lie in [{x0}, {x1}] and y in \
                 [{y0}, {y1}] (an origin far from the pixels makes the estimate ill-conditioned)",
                crate::groundtruth::fmt_num(o[0]),
                crate::groundtruth::fmt_num(o[1]),
            ),
        ));
    }
    Ok(())
}

/// Relative tolerance of the positive semi-definiteness check: an eigenvalue below
/// `−PSD_TOLERANCE × the largest one` is a real negative variance, not rounding.
const PSD_TOLERANCE: f64 = 1e-9;

/// Whether an estimate may be reported as a result: finite parameters, a covariance that is
/// finite, symmetric and positive semi-definite with a positive variance for every parameter,
/// and an estimate that converged and that motion-est flags as reliable.
///
/// # Errors
/// Why the estimate must not be reported.
pub fn assess(est: &MotionEstimate) -> std::result::Result<(), String> {
    let n = est.params.len();
    if est.params.iter().any(|v| !v.is_finite()) {
        return Err("the parameters are not finite".to_owned());
    }
    if est.covariance.len() != n * n || est.covariance.iter().any(|v| !v.is_finite()) {
        return Err("the covariance is not finite".to_owned());
    }
    let c = nalgebra::DMatrix::from_row_slice(n, n, &est.covariance);
    let scale = c.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if (&c - c.transpose()).amax() > PSD_TOLERANCE * scale.max(f64::MIN_POSITIVE) {
        return Err("the covariance is not symmetric".to_owned());
    }
    if let Some(i) = (0..n).find(|&i| c[(i, i)] <= 0.0) {
        return Err(format!(
            "the variance of parameter {i} is {}, not positive: the covariance is not positive \
             definite",
            c[(i, i)]
        ));
    }
    let eig = nalgebra::SymmetricEigen::new(0.5 * (&c + c.transpose())).eigenvalues;
    let (min, max) = eig.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), &v| {
        (lo.min(v), hi.max(v))
    });
    if min < -PSD_TOLERANCE * max {
        return Err(format!(
            "the covariance is not positive semi-definite (eigenvalue {min:e})"
        ));
    }
    if !est.converged {
        return Err(format!(
            "the estimate did not converge at full resolution (iterations per level {:?})",
            est.iterations
        ));
    }
    if !est.reliable {
        return Err(format!(
            "motion-est flags the estimate unreliable: no dominant motion could be separated \
             (inliers {:.1} %, noise scale {:.3} grey levels)",
            100.0 * est.inlier_fraction,
            est.scale
        ));
    }
    Ok(())
}

/// The JSON object of a failed estimate: `"status": "failed"`, the reason and the diagnostics,
/// but no `params` and no `covariance`, which do not describe the region's motion.
fn failure_json(est: &MotionEstimate, reason: &str, millis: f64) -> String {
    serde_json::json!({
        "status": "failed",
        "reason": reason,
        "model": est.spec.model.name(),
        "offset": est.spec.offset,
        "origin": est.origin,
        "scale": finite_or_null(est.scale),
        "inlier_fraction": finite_or_null(est.inlier_fraction),
        "iterations": est.iterations,
        "converged": est.converged,
        "reliable": est.reliable,
        "millis": millis,
    })
    .to_string()
}

/// The JSON failure object when the estimator returned no estimate: the reason and the model
/// asked for, nothing measured.
fn failure_json_without(spec: ModelSpec, origin: Option<[f64; 2]>, reason: &str) -> String {
    serde_json::json!({
        "status": "failed",
        "reason": reason,
        "model": spec.model.name(),
        "offset": spec.offset,
        "origin": origin,
    })
    .to_string()
}

fn finite_or_null(v: f64) -> serde_json::Value {
    if v.is_finite() {
        serde_json::json!(v)
    } else {
        serde_json::Value::Null
    }
}

/// The JSON object of a reliable estimate ([`assess`]): status `ok`, model, params, covariance (row-major), origin, scale,
/// inlier_fraction, iterations (per level, 0 = full resolution), converged, reliable (false when
/// the dominant motion could not be separated from the rest: treat the estimate as failed;
/// `motion_est::MotionEstimate::reliable`), millis.
fn to_json(est: &MotionEstimate, millis: f64) -> String {
    let value = serde_json::json!({
        "status": "ok",
        "model": est.spec.model.name(),
        "offset": est.spec.offset,
        "params": est.params,
        "covariance": est.covariance,
        "origin": est.origin,
        "scale": est.scale,
        "inlier_fraction": est.inlier_fraction,
        "iterations": est.iterations,
        "converged": est.converged,
        "reliable": est.reliable,
        "millis": millis,
    });
    value.to_string()
}

fn to_text(est: &MotionEstimate, millis: f64) -> String {
    let n = est.params.len();
    let sd: Vec<String> = (0..n)
        .map(|i| format!("{:.3e}", est.covariance[i * n + i].max(0.0).sqrt()))
        .collect();
    let p: Vec<String> = est.params.iter().map(|v| format!("{v:.6}")).collect();
    format!(
        "model {}{}\nparams [{}]\nstd    [{}]\norigin ({:.2}, {:.2})\nscale {:.3} grey levels, inliers {:.1} %, iterations {:?}, converged {}, reliable {}, {:.2} ms",
        est.spec.model.name(),
        if est.spec.offset { " + offset" } else { "" },
        p.join(", "),
        sd.join(", "),
        est.origin[0],
        est.origin[1],
        est.scale,
        100.0 * est.inlier_fraction,
        est.iterations,
        est.converged,
        est.reliable,
        millis
    )
}

fn parse_floats<const N: usize>(name: &str, s: &str) -> Result<[f64; N]> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != N {
        return Err(AppError::setting(
            name,
            format!("expected {N} comma-separated numbers, got `{s}`"),
        ));
    }
    let mut out = [0.0; N];
    for (o, p) in out.iter_mut().zip(&parts) {
        let v: f64 = p
            .parse()
            .map_err(|_| AppError::setting(name, format!("`{p}` is not a number")))?;
        if !v.is_finite() {
            return Err(AppError::setting(name, format!("`{p}` is not finite")));
        }
        *o = v;
    }
    Ok(out)
}

/// Loads an image as grey f32 in 0–255 (16-bit images keep their precision).
fn load_grey(path: &Path) -> Result<(usize, usize, Vec<f32>)> {
    let img = crate::sequence::decode_image(path)?;
    let grey = img.into_luma16();
    let (w, h) = (grey.width() as usize, grey.height() as usize);
    let data = grey
        .into_raw()
        .into_iter()
        .map(|v| f32::from(v) / 257.0)
        .collect();
    Ok((w, h, data))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write_png(path: &Path, w: u32, h: u32, f: impl Fn(f64, f64) -> f64) {
        let img = image::GrayImage::from_fn(w, h, |x, y| {
            image::Luma([f(f64::from(x), f64::from(y)).round().clamp(0.0, 255.0) as u8])
        });
        img.save(path).unwrap();
    }

    fn tex(x: f64, y: f64) -> f64 {
        128.0
            + 40.0 * (0.31 * x + 0.1 * y).sin()
            + 30.0 * (0.23 * y - 0.05 * x).cos()
            + 20.0 * (0.5 * x + 0.4 * y).sin()
    }

    #[test]
    fn json_output_has_the_issue_keys_and_recovers_a_shift() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
        write_png(&a, 96, 80, tex);
        // Second frame: the texture moved by (2, −1) px.
        write_png(&b, 96, 80, |x, y| tex(x - 2.0, y + 1.0));
        let args = Args {
            frame0: a.clone(),
            frame1: b.clone(),
            roi: Some("10,10,70,60".into()),
            mask: None,
            model: ModelArg::Translation,
            offset: false,
            origin: None,
            tolerance: DEFAULT_TOLERANCE,
            json: true,
        };
        run(&args).unwrap();
        // The JSON itself, built from the same estimate the command prints.
        let (w, h, f0) = load_grey(&a).unwrap();
        let (_, _, f1) = load_grey(&b).unwrap();
        let est = MotionEstimator::new(settings(DEFAULT_TOLERANCE))
            .unwrap()
            .estimate_images(
                GreyImage::new(w, h, &f0).unwrap(),
                GreyImage::new(w, h, &f1).unwrap(),
                &Region::Rect {
                    x: 10.0,
                    y: 10.0,
                    width: 70.0,
                    height: 60.0,
                },
                ModelSpec::new(MotionModel::Translation, false),
                None,
            )
            .unwrap();
        let v: serde_json::Value = serde_json::from_str(&to_json(&est, 1.0)).unwrap();
        for key in [
            "model",
            "params",
            "covariance",
            "origin",
            "scale",
            "inlier_fraction",
            "iterations",
            "converged",
            "reliable",
            "millis",
        ] {
            assert!(v.get(key).is_some(), "missing {key}");
        }
        assert_eq!(v["model"], "translation");
        assert_eq!(v["covariance"].as_array().unwrap().len(), 4);
        // 8-bit rounding of a smooth texture: 0.05 px is generous for a 70×60 region.
        let p = v["params"].as_array().unwrap();
        assert!((p[0].as_f64().unwrap() - 2.0).abs() < 0.05, "{p:?}");
        assert!((p[1].as_f64().unwrap() + 1.0).abs() < 0.05, "{p:?}");
        assert_eq!(v["origin"][0].as_f64().unwrap(), 44.5);
    }

    #[test]
    fn bad_arguments_are_reported() {
        assert_eq!(
            parse_floats::<4>("--roi", "1,2,3").unwrap_err().exit_code(),
            2
        );
        assert_eq!(
            parse_floats::<2>("--origin", "1,x")
                .unwrap_err()
                .exit_code(),
            2
        );
        assert_eq!(
            parse_floats::<2>("--origin", " 3.5 , 4").unwrap(),
            [3.5, 4.0]
        );
        let args = Args {
            frame0: "/nonexistent/a.png".into(),
            frame1: "/nonexistent/b.png".into(),
            roi: None,
            mask: None,
            model: ModelArg::Affine,
            offset: false,
            origin: None,
            tolerance: DEFAULT_TOLERANCE,
            json: false,
        };
        assert_eq!(run(&args).unwrap_err().exit_code(), 3);
    }
}
