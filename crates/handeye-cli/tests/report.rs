//! `calibrate --report FILE.html` and `online --report FILE.html`: one self-contained page whose
//! every figure renders in a real browser (headless Chromium, which `.ci/run` installs; without `CI` set, a missing browser
//! skips only the rendering).

use std::path::{Path, PathBuf};
use std::process::Command;

fn testdata(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata")
        .join(rel)
}

/// The page for a kinhec file with planted outliers.
fn page(dir: &Path) -> PathBuf {
    let path = dir.join("report.html");
    let out = Command::new(env!("CARGO_BIN_EXE_handeye"))
        .args(["calibrate", "--output", "json", "--report"])
        .arg(&path)
        .arg(testdata(
            "kinhec/pairs/outliers_gross_stations_eih_s0.jsonl",
        ))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    path
}

#[test]
fn the_report_is_one_self_contained_page_with_three_figures() {
    let dir = tempfile::tempdir().unwrap();
    let html = std::fs::read_to_string(page(dir.path())).unwrap();
    assert_eq!(html.matches("<svg").count(), 3);
    assert_eq!(html.matches("<figcaption>").count(), 3);
    // Nothing is fetched: no link, script or image source; URLs only as SVG's namespace.
    for needle in ["href=", "src=", "<link", "<script", "<img"] {
        assert!(!html.contains(needle), "{needle}");
    }
    let urls = html.matches("http").count();
    assert_eq!(urls, html.matches("http://www.w3.org/2000/svg").count());
    // The numbers a person needs, with their units, and the outliers' warning.
    assert!(html.contains("X = gripper_from_camera") && html.contains("one-sigma"));
    assert!(html.contains("(°)") && html.contains("disagree with the others"));
}

/// Chromium's binary, if installed.
fn chromium() -> Option<&'static str> {
    ["chromium", "chromium-browser"].into_iter().find(|b| {
        Command::new(b)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

/// The online page for a kinhec stream with planted outliers.
fn online_page(dir: &Path) -> PathBuf {
    let path = dir.join("online.html");
    let streams = testdata("kinhec/streams");
    let out = Command::new(env!("CARGO_BIN_EXE_handeye"))
        .args([
            "online",
            "--output",
            "json",
            "--estimator",
            "accumulate",
            "--time-offset",
            "auto",
        ])
        .arg("--robot")
        .arg(streams.join("temporal_outliers_gross_30hz_eih_s2_robot.txt"))
        .arg("--camera")
        .arg(streams.join("temporal_outliers_gross_30hz_eih_s2_camera.txt"))
        .arg("--report")
        .arg(&path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    path
}

#[test]
fn every_figure_renders_in_headless_chromium() {
    let Some(browser) = chromium() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must install chromium (.ci/run)"
        );
        eprintln!("chromium not installed: rendering not checked");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    // The online page of two streams also draws the clock-offset correlation.
    for (path, figures) in [(page(dir.path()), 3), (online_page(dir.path()), 4)] {
        rendered(browser, &path, figures, dir.path());
    }
}

/// Renders `path` and checks that its `figures` figures are laid out and that the page is not
/// blank.
fn rendered(browser: &str, path: &Path, figures: usize, dir: &Path) {
    let flags = [
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
    ];
    let profile = dir.join("profile");
    // The rendered DOM, with each figure's size as laid out.
    let probe = dir.join("probe.html");
    let html = std::fs::read_to_string(path).unwrap();
    assert_eq!(html.matches("<svg").count(), figures, "{}", path.display());
    let script = "<script>window.onload=()=>{const s=[...document.querySelectorAll('figure svg')];document.title='rendered:'+s.filter(e=>{const r=e.getBoundingClientRect();return r.width>100&&r.height>100&&e.querySelectorAll('*').length>20}).length+'/'+s.length;};</script>";
    std::fs::write(&probe, html.replace("</body>", &format!("{script}</body>"))).unwrap();
    let dom = Command::new(browser)
        .args(flags)
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(["--virtual-time-budget=5000", "--dump-dom"])
        .arg(format!("file://{}", probe.display()))
        .output()
        .unwrap();
    let dom_text = String::from_utf8_lossy(&dom.stdout);
    assert!(
        dom_text.contains(&format!("<title>rendered:{figures}/{figures}</title>")),
        "{}: {}",
        path.display(),
        &dom_text[..dom_text.len().min(400)]
    );
    // A screenshot that is not blank: a PNG of some size.
    let png = dir.join("shot.png");
    let _ = std::fs::remove_file(&png);
    let shot = Command::new(browser)
        .args(flags)
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(["--window-size=1000,1400", "--hide-scrollbars"])
        .arg(format!("--screenshot={}", png.display()))
        .arg(format!("file://{}", path.display()))
        .output()
        .unwrap();
    let bytes = std::fs::read(&png)
        .unwrap_or_else(|_| panic!("no screenshot: {}", String::from_utf8_lossy(&shot.stderr)));
    assert!(
        bytes.starts_with(b"\x89PNG") && bytes.len() > 20_000,
        "{}: {} bytes",
        path.display(),
        bytes.len()
    );
}
