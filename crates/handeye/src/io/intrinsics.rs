//! Camera intrinsics (`--intrinsics FILE`, SPEC sec. 9): OpenCV's FileStorage YAML
//! (`camera_matrix`, `distortion_coefficients` k1 k2 p1 p2 k3, `image_width`, `image_height`; a
//! `%YAML:1.0` first line and `!!opencv-matrix` mappings with `rows`, `cols`, `dt`, `data`), the
//! same names as ROS's `camera_calibration_parsers` writes them, or a ROS `camera_info` message
//! (`k`/`K`, `d`/`D`, `width`, `height`, `distortion_model`), or ViSP's camera XML
//! (`vpXmlParserCamera`: one `<camera>`, its `<model>` `px py u0 v0` and, for
//! `perspectiveProjWithDistortion`, `kud`, which is OpenCV's k1).
//!
//! Parsed by the readers' YAML tree (`yaml-rust2`'s event parser, every value with its line), so
//! errors name the line. OpenCV's `%YAML:1.0` is not a valid YAML directive (YAML writes
//! `%YAML 1.0`): that one line is blanked before parsing, so line numbers stay the file's.

use std::path::Path;

use crate::io::parse_error;
use crate::io::yaml_tree::YamlTree;
use crate::model::camera::Intrinsics;
use crate::model::error::Result;

impl Intrinsics {
    /// Reads the intrinsics of a file: OpenCV's calibration YAML (`camera_matrix`,
    /// `distortion_coefficients`, `image_width`, `image_height`), the same names as ROS's
    /// `camera_calibration_parsers` writes them, or a ROS `camera_info` message (`k`/`K`,
    /// `d`/`D`, `width`, `height`, `distortion_model`). Errors name the file, the line and the
    /// field.
    pub fn read(path: impl AsRef<Path>) -> Result<Intrinsics> {
        let path = path.as_ref();
        // Read as every whole-file format is: a file or a pipe, of bounded size.
        let text = crate::io::read_text(path)?;
        parse_intrinsics(&text, &path.display().to_string())
    }
}

/// Parses intrinsics from the text of a file named `file` in messages.
///
/// # Example
/// ```
/// let text = "%YAML:1.0\n---\nimage_width: 1280\nimage_height: 720\n\
///     camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   \
///     data: [ 900., 0., 640., 0., 901., 360., 0., 0., 1. ]\n\
///     distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   \
///     data: [ -0.2, 0.1, 0., 0., 0. ]\n";
/// let k = handeye::io::parse_intrinsics(text, "camera.yml")?;
/// assert_eq!((k.fx, k.fy, k.cx, k.cy, k.width), (900.0, 901.0, 640.0, 360.0, 1280));
/// assert_eq!(k.distortion[0], -0.2);
/// # Ok::<(), handeye::Error>(())
/// ```
pub fn parse_intrinsics(text: &str, file: &str) -> Result<Intrinsics> {
    if text.trim_start().starts_with('<') {
        return parse_visp_xml(text, file);
    }
    let tree = YamlTree::parse(&opencv_header_blanked(text), file)?;
    let err = |field: &str, message: String| {
        parse_error(file, tree.line(field).unwrap_or(0), field, message)
    };
    for names in [
        &["camera_matrix", "k", "K"][..],
        &["distortion_coefficients", "d", "D"],
        &["image_width", "width"],
        &["image_height", "height"],
    ] {
        one_of(&tree, names, file)?;
    }
    let k_name = first_of(&tree, &["camera_matrix", "k", "K"]).ok_or_else(|| {
        err(
            "camera_matrix",
            "missing: give `camera_matrix` (OpenCV) or `k` (ROS camera_info)".into(),
        )
    })?;
    let k = numbers(&tree, k_name, file)?;
    if k.len() != 9 {
        return Err(err(
            k_name,
            format!("{} numbers, expected 9 (3×3)", k.len()),
        ));
    }
    if k[1] != 0.0 || k[3] != 0.0 || k[6] != 0.0 || k[7] != 0.0 || k[8] != 1.0 {
        return Err(err(
            k_name,
            format!(
                "expected [fx 0 cx; 0 fy cy; 0 0 1], got {k:?} (a skewed or unnormalised matrix is not supported)"
            ),
        ));
    }
    let d_name = first_of(&tree, &["distortion_coefficients", "d", "D"]).ok_or_else(|| {
        err(
            "distortion_coefficients",
            "missing: give `distortion_coefficients` (OpenCV) or `d` (ROS camera_info); `data: [0, 0, 0, 0, 0]` for none".into(),
        )
    })?;
    let d = numbers(&tree, d_name, file)?;
    if let Some((model, _)) = tree.text("distortion_model")
        && !matches!(model, "plumb_bob" | "rational_polynomial" | "radtan" | "")
    {
        return Err(err(
            "distortion_model",
            format!("`{model}` is not supported: plumb_bob (k1 k2 p1 p2 k3) only"),
        ));
    }
    let distortion = distortion(&d).map_err(|m| err(d_name, m))?;
    let size = |names: &[&'static str]| -> Result<u32> {
        match first_of(&tree, names) {
            None => Ok(0),
            Some(name) => {
                let text = tree.text(name).map_or("", |(t, _)| t);
                text.trim()
                    .parse::<u32>()
                    .map_err(|_| err(name, format!("expected a size in pixels, got `{text}`")))
            }
        }
    };
    let width = size(&["image_width", "width"])?;
    let intrinsics = pinhole(&k, distortion, (width, size(&["image_height", "height"])?));
    intrinsics.check().map_err(|(field, message)| {
        // The field as the file names it: the camera matrix's entry, the distortion's list, the
        // image's size.
        let (name, path) = match field {
            "distortion" => (d_name, d_name.to_string()),
            "width" | "height" => {
                let name =
                    first_of(&tree, &[field, "image_width", "image_height"]).unwrap_or(field);
                (name, name.to_string())
            }
            _ => (k_name, format!("{k_name}.{field}")),
        };
        parse_error(file, tree.line(name).unwrap_or(0), path, message)
    })?;
    Ok(intrinsics)
}

/// The intrinsics of a ROS `sensor_msgs/msg/CameraInfo` message (`k`, `d`, `distortion_model`,
/// `width`, `height`), or what is wrong with them, naming the field.
#[cfg(feature = "rosbag")]
pub(crate) fn intrinsics_of_camera_info(
    k: &[f64; 9],
    d: &[f64],
    model: &str,
    (width, height): (u32, u32),
) -> std::result::Result<Intrinsics, String> {
    if k[1] != 0.0 || k[3] != 0.0 || k[6] != 0.0 || k[7] != 0.0 || k[8] != 1.0 {
        return Err(format!(
            "`k`: expected [fx 0 cx; 0 fy cy; 0 0 1], got {k:?} (a skewed or unnormalised matrix is not supported; all zeros: the camera is not calibrated)"
        ));
    }
    if !matches!(model, "plumb_bob" | "rational_polynomial" | "radtan" | "") {
        return Err(format!(
            "`distortion_model`: `{model}` is not supported: plumb_bob (k1 k2 p1 p2 k3) only"
        ));
    }
    let distortion = distortion(d).map_err(|m| format!("`d`: {m}"))?;
    let intrinsics = pinhole(k, distortion, (width, height));
    intrinsics
        .check()
        .map_err(|(field, message)| format!("`k` ({field}): {message}"))?;
    Ok(intrinsics)
}

/// The intrinsics of the camera matrix `k` (row-major [fx 0 cx; 0 fy cy; 0 0 1], checked by the
/// caller), with `distortion` and the image size.
fn pinhole(k: &[f64], distortion: [f64; 5], (width, height): (u32, u32)) -> Intrinsics {
    Intrinsics {
        fx: k[0],
        fy: k[4],
        cx: k[2],
        cy: k[5],
        distortion,
        width,
        height,
    }
}

/// The text with OpenCV's `%YAML:1.0` first line blanked.
fn opencv_header_blanked(text: &str) -> String {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    match text.split_once('\n') {
        Some((first, rest)) if first.trim_end().starts_with("%YAML:") => format!("\n{rest}"),
        _ => text.to_string(),
    }
}

/// Refuses a file that gives more than one of `names` (OpenCV's `camera_matrix` and ROS's `k`,
/// say): one would be read and the other ignored, and which was meant is not known.
fn one_of(tree: &YamlTree, names: &[&'static str], file: &str) -> Result<()> {
    let given: Vec<(&str, usize)> = names
        .iter()
        .filter_map(|n| Some((*n, tree.line(n)?)))
        .collect();
    if let [(first, _), (second, line), ..] = given[..] {
        return Err(parse_error(
            file,
            line,
            second,
            format!(
                "both `{first}` and `{second}` given: one would be read and the other ignored; keep one"
            ),
        ));
    }
    Ok(())
}

/// The first of `names` the file gives.
fn first_of(tree: &YamlTree, names: &[&'static str]) -> Option<&'static str> {
    names.iter().copied().find(|n| tree.line(n).is_some())
}

/// The numbers of the matrix `name`: an `!!opencv-matrix` (or ROS's) mapping with `data` (and
/// `rows`, `cols` that must agree), or a list of numbers (or of rows of numbers). Errors are the
/// matrix's, at the line of the offending entry.
fn numbers(tree: &YamlTree, name: &str, file: &str) -> Result<Vec<f64>> {
    let data = format!("{name}.data");
    let list = if tree.line(&data).is_some() {
        data
    } else {
        name.to_string()
    };
    let at = |path: &str, message: String| {
        parse_error(
            file,
            tree.line(path).or(tree.line(name)).unwrap_or(0),
            name,
            message,
        )
    };
    let count = tree
        .sequence(&list, "a list of numbers")
        .map_err(|_| at(&list, format!("`{list}`: expected a list of numbers")))?;
    let mut out = Vec::with_capacity(count);
    for i in 0..count {
        let item = format!("{list}[{i}]");
        let row = tree.sequence(&item, "").ok();
        // A list of rows: every row as long as the first.
        if let (Some(n), Some(first)) = (row, tree.sequence(&format!("{list}[0]"), "").ok())
            && n != first
        {
            return Err(at(
                &item,
                format!(
                    "`{item}`: a row of {n} numbers after a first of {first}: rows must be as long as each other"
                ),
            ));
        }
        let paths: Vec<String> = match row {
            Some(n) => (0..n).map(|j| format!("{item}[{j}]")).collect(),
            None => vec![item],
        };
        for path in paths {
            let x = tree
                .number(&path, "a number")
                .map_err(|_| at(&path, format!("`{path}`: expected a finite number")))?;
            out.push(x);
        }
    }
    // `rows` and `cols`, where given: counts that agree with `data`.
    let size = |field: &str| -> Result<Option<usize>> {
        let path = format!("{name}.{field}");
        match tree.text(&path) {
            None => Ok(None),
            Some((t, _)) => match t.trim().parse::<usize>() {
                Ok(n) if n > 0 => Ok(Some(n)),
                _ => Err(at(
                    &path,
                    format!("`{path}`: `{t}` is not a count of rows or columns"),
                )),
            },
        }
    };
    if let (Some(rows), Some(cols)) = (size("rows")?, size("cols")?)
        && rows.checked_mul(cols) != Some(out.len())
    {
        return Err(at(
            name,
            format!(
                "rows {rows} × cols {cols} but {} numbers in `data`",
                out.len()
            ),
        ));
    }
    Ok(out)
}

/// k1 k2 p1 p2 k3 from OpenCV's 4, 5, 8, 12 or 14 coefficients (those past the fifth must be 0:
/// the rational and thin-prism terms are not modelled).
fn distortion(d: &[f64]) -> std::result::Result<[f64; 5], String> {
    match d.len() {
        0 | 4 | 5 | 8 | 12 | 14 => {}
        n => {
            return Err(format!(
                "{n} coefficients, expected 4, 5, 8, 12 or 14 (k1 k2 p1 p2 [k3 …])"
            ));
        }
    }
    if d.iter().skip(5).any(|x| *x != 0.0) {
        return Err(
            "coefficients past k3 are not zero: the rational and thin-prism terms are not supported"
                .into(),
        );
    }
    let mut out = [0.0; 5];
    for (o, x) in out.iter_mut().zip(d) {
        *o = *x;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::error::Error;

    /// Read as every whole-file format is: a device or a directory is refused by name, never read
    /// (an endless `/dev/zero` was read into memory before).
    #[cfg(unix)]
    #[test]
    fn a_device_or_a_directory_is_refused_not_read() {
        for path in ["/dev/zero", "/"] {
            match Intrinsics::read(path) {
                Err(Error::Parse { file, message, .. }) => {
                    assert_eq!(file, path);
                    assert!(message.contains("not a file"), "{message}");
                }
                other => panic!("{path}: {other:?}"),
            }
        }
    }

    const OPENCV: &str = "%YAML:1.0\n---\ncalibration_time: \"x\"\nimage_width: 1280\nimage_height: 720\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ 9.0500000000000000e+02, 0., 6.412e+02, 0.,\n       9.0350000000000000e+02, 3.587e+02, 0., 0., 1. ]\ndistortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: [ -2.1e-01, 9.0e-02, 7.0e-04, -4.0e-04, -1.5e-02 ]\n";

    #[test]
    fn reads_opencv_filestorage() {
        let k = parse_intrinsics(OPENCV, "c.yml").unwrap();
        assert_eq!((k.fx, k.fy, k.cx, k.cy), (905.0, 903.5, 641.2, 358.7));
        assert_eq!(k.distortion, [-0.21, 0.09, 0.0007, -0.0004, -0.015]);
        assert_eq!((k.width, k.height), (1280, 720));
    }

    #[test]
    fn reads_ros_camera_info() {
        let ros2 = "header:\n  frame_id: cam\nheight: 480\nwidth: 640\ndistortion_model: plumb_bob\nd: [0.1, -0.2, 0.0, 0.0, 0.0]\nk: [500.0, 0.0, 320.0, 0.0, 501.0, 240.0, 0.0, 0.0, 1.0]\n";
        let k = parse_intrinsics(ros2, "info.yaml").unwrap();
        assert_eq!(
            (k.fx, k.fy, k.cx, k.cy, k.width),
            (500.0, 501.0, 320.0, 240.0, 640)
        );
        let ros1 = "height: 480\nwidth: 640\nD: [0.1, -0.2, 0.0, 0.0]\nK: [500, 0, 320, 0, 501, 240, 0, 0, 1]\n";
        assert_eq!(
            parse_intrinsics(ros1, "info.yaml").unwrap().distortion[1],
            -0.2
        );
    }

    #[test]
    fn bad_files_name_the_field() {
        let field = |text: &str| match parse_intrinsics(text, "c.yml") {
            Err(Error::Parse { field, .. }) => field,
            other => panic!("{other:?}"),
        };
        let no_distortion = OPENCV.split("distortion_coefficients").next().unwrap();
        assert_eq!(field(no_distortion), "distortion_coefficients");
        assert_eq!(field("image_width: 3\n"), "camera_matrix");
        assert_eq!(
            field(&OPENCV.replace("rows: 3\n   cols: 3", "rows: 3\n   cols: 4")),
            "camera_matrix"
        );
        assert_eq!(
            field(&OPENCV.replace("9.0500000000000000e+02", "-1.")),
            "camera_matrix.fx"
        );
        assert_eq!(
            field(&OPENCV.replace("-2.1e-01", ".nan")),
            "distortion_coefficients"
        );
        assert_eq!(field("k: [1, 2\n"), "-");
        // Every error has its line: the entry, the matrix, or the missing field's place.
        let line = |text: &str| match parse_intrinsics(text, "c.yml") {
            Err(Error::Parse { line, .. }) => line,
            other => panic!("{other:?}"),
        };
        assert_eq!(line(&OPENCV.replace("-2.1e-01", ".nan")), 16);
        assert_eq!(
            line(&OPENCV.replace("6.412e+02, 0.,\n", "6.412e+02, 0.,\n       9.0, ")),
            6
        );
        assert_eq!(
            field(&format!("{OPENCV}distortion_model: equidistant\n")),
            "distortion_model"
        );
    }

    /// What cannot be a camera's is refused, naming the field (issue 59): two sets of one field
    /// (OpenCV's and ROS's names), counts of rows that are not counts, ragged rows, absurd but
    /// finite numbers, a NUL byte.
    #[test]
    fn a_file_that_cannot_be_one_camera_s_is_refused_at_the_field() {
        let refused = |text: &str| match parse_intrinsics(text, "c.yml") {
            Err(Error::Parse {
                line,
                field,
                message,
                ..
            }) => (line, field, message),
            other => panic!("{other:?}"),
        };
        let (line, field, message) =
            refused(&format!("{OPENCV}k: [900, 0, 640, 0, 900, 360, 0, 0, 1]\n"));
        assert_eq!((line, field.as_str()), (17, "k"), "{message}");
        assert!(
            message.contains("both `camera_matrix` and `k`"),
            "{message}"
        );
        let (_, field, _) = refused(&format!("{OPENCV}d: [0, 0, 0, 0, 0]\n"));
        assert_eq!(field, "d");
        let (_, field, message) =
            refused(&OPENCV.replace("rows: 3\n   cols: 3", "rows: x\n   cols: 3"));
        assert_eq!(field, "camera_matrix", "{message}");
        assert!(message.contains("`x` is not a count"), "{message}");
        let ragged = "k: [[900, 0, 640], [0, 900], [360, 0, 0, 1]]\nd: [0, 0, 0, 0, 0]\n";
        let (line, _, message) = refused(ragged);
        assert_eq!(line, 1);
        assert!(message.contains("rows must be as long"), "{message}");
        for (from, to, field, line) in [
            ("9.0500000000000000e+02", "1e-300", "camera_matrix.fx", 6),
            ("6.412e+02", "1e308", "camera_matrix.cx", 6),
            ("-2.1e-01", "1e300", "distortion_coefficients", 12),
            ("1280", "4000000000", "image_width", 4),
        ] {
            let (at, got, message) = refused(&OPENCV.replace(from, to));
            assert_eq!((got.as_str(), at), (field, line), "{message}");
        }
        let text = parse_intrinsics(&OPENCV.replace("9.0500000000000000e+02", "905"), "c.yml");
        assert!(text.is_ok(), "{text:?}");
    }
}

/// One `<model>` of ViSP's camera XML: its type and its numbers by name, each with its line.
#[derive(Default)]
struct VispModel {
    kind: String,
    values: Vec<(String, f64, usize)>,
}

/// ViSP's camera XML (`vpXmlParserCamera`): one `<camera>` with `image_width`, `image_height` and
/// its `<model>`s; `perspectiveProjWithDistortion` (k1 = `kud`) is taken when given, else
/// `perspectiveProjWithoutDistortion`.
fn parse_visp_xml(text: &str, file: &str) -> Result<Intrinsics> {
    use quick_xml::events::Event;
    let line_at = |pos: u64| {
        let pos = usize::try_from(pos).unwrap_or(usize::MAX).min(text.len());
        text.as_bytes()[..pos]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1
    };
    let mut reader = quick_xml::Reader::from_str(text);
    let (mut path, mut models, mut cameras) = (Vec::<String>::new(), Vec::<VispModel>::new(), 0);
    let mut size: [Option<u32>; 2] = [None, None];
    loop {
        let at = line_at(reader.buffer_position());
        match reader.read_event() {
            Err(e) => return Err(parse_error(file, at, "xml", e.to_string())),
            Ok(Event::Eof) => break,
            Ok(Event::Start(tag)) => {
                let name = tag.name().as_ref().to_owned();
                if name == "camera" {
                    cameras += 1;
                } else if name == "model" {
                    models.push(VispModel::default());
                }
                if path.len() > 16 {
                    return Err(parse_error(
                        file,
                        at,
                        name,
                        "nested too deep for a camera file",
                    ));
                }
                path.push(name);
            }
            Ok(Event::End(_)) => {
                path.pop();
            }
            Ok(Event::Text(t)) => {
                let value = t.xml10_content();
                let value = value.trim();
                let Some(field) = path.last().cloned() else {
                    continue;
                };
                let in_model = path.iter().any(|p| p == "model");
                let number = || {
                    value.parse::<f64>().map_err(|_| {
                        parse_error(
                            file,
                            at,
                            field.as_str(),
                            format!("`{value}` is not a number"),
                        )
                    })
                };
                match (in_model, field.as_str()) {
                    (true, "type") => {
                        if let Some(m) = models.last_mut() {
                            m.kind = value.to_owned();
                        }
                    }
                    (true, "px" | "py" | "u0" | "v0" | "kud") => {
                        let v = number()?;
                        if let Some(m) = models.last_mut() {
                            m.values.push((field.clone(), v, at));
                        }
                    }
                    (false, "image_width" | "image_height") => {
                        let v = value.parse::<u32>().map_err(|_| {
                            parse_error(
                                file,
                                at,
                                field.as_str(),
                                format!("expected a size in pixels, got `{value}`"),
                            )
                        })?;
                        size[usize::from(field == "image_height")] = Some(v);
                    }
                    _ => {}
                }
            }
            Ok(_) => {}
        }
    }
    if cameras != 1 {
        return Err(parse_error(
            file,
            0,
            "camera",
            format!("{cameras} <camera> entries: the intrinsics are one camera's (keep one)"),
        ));
    }
    let with = models
        .iter()
        .find(|m| m.kind == "perspectiveProjWithDistortion");
    let model = with
        .or_else(|| models.iter().find(|m| m.kind == "perspectiveProjWithoutDistortion"))
        .ok_or_else(|| {
            parse_error(
                file,
                0,
                "model",
                "no <model> of type perspectiveProjWithDistortion or perspectiveProjWithoutDistortion",
            )
        })?;
    let get = |name: &str| -> Result<f64> {
        model
            .values
            .iter()
            .find(|(n, _, _)| n == name)
            .map(|(_, v, _)| *v)
            .ok_or_else(|| parse_error(file, 0, format!("model.{name}"), "missing"))
    };
    let k1 = if with.is_some() { get("kud")? } else { 0.0 };
    let k = [
        get("px")?,
        0.0,
        get("u0")?,
        0.0,
        get("py")?,
        get("v0")?,
        0.0,
        0.0,
        1.0,
    ];
    let intrinsics = pinhole(
        &k,
        [k1, 0.0, 0.0, 0.0, 0.0],
        (size[0].unwrap_or(0), size[1].unwrap_or(0)),
    );
    intrinsics
        .check()
        .map_err(|(field, message)| parse_error(file, 0, format!("model.{field}"), message))?;
    Ok(intrinsics)
}

#[cfg(test)]
mod visp_xml_tests {
    use super::parse_intrinsics;

    const XML: &str = r#"<?xml version="1.0"?>
<root>
  <camera>
    <name>Camera</name>
    <image_width>640</image_width>
    <image_height>480</image_height>
    <model>
      <type>perspectiveProjWithoutDistortion</type>
      <px>600.5</px>
      <py>601.5</py>
      <u0>320.25</u0>
      <v0>240.75</v0>
    </model>
    <model>
      <type>perspectiveProjWithDistortion</type>
      <px>610.5</px>
      <py>611.5</py>
      <u0>321.25</u0>
      <v0>241.75</v0>
      <kud>-0.125</kud>
      <kdu>0.13</kdu>
    </model>
  </camera>
</root>
"#;

    #[test]
    fn visp_xml_gives_the_model_with_distortion() {
        let k = parse_intrinsics(XML, "camera.xml").unwrap();
        assert_eq!((k.fx, k.fy, k.cx, k.cy), (610.5, 611.5, 321.25, 241.75));
        assert_eq!(k.distortion, [-0.125, 0.0, 0.0, 0.0, 0.0]);
        assert_eq!((k.width, k.height), (640, 480));
        let plain = XML.replace("perspectiveProjWithDistortion", "other");
        let k = parse_intrinsics(&plain, "camera.xml").unwrap();
        assert_eq!((k.fx, k.distortion[0]), (600.5, 0.0));
    }

    #[test]
    fn bad_visp_xml_names_the_line_and_field() {
        let e = parse_intrinsics(&XML.replace("<px>610.5", "<px>six"), "c.xml").unwrap_err();
        assert!(e.to_string().contains("c.xml:16"), "{e}");
        assert!(e.to_string().contains("px"), "{e}");
        let e = parse_intrinsics(&XML.replace("<kud>-0.125</kud>", ""), "c.xml").unwrap_err();
        assert!(e.to_string().contains("kud"), "{e}");
        let two = XML.replace("</root>", "<camera></camera></root>");
        let e = parse_intrinsics(&two, "c.xml").unwrap_err();
        assert!(e.to_string().contains("2 <camera>"), "{e}");
    }
}
