//! Parity with OpenCV 4.14's `calibrateHandEye` on testdata/opencv (see testdata/FIXTURES.md) and
//! on two small pose sets embedded below: with all pose pairs, each method OpenCV shares with us
//! gives OpenCV's answer to 1e-6 (max abs entry of the 4×4 matrix); and on the noisy sets our
//! `andreff` and `refine` are compared with OpenCV's methods against the true transform.
//!
//! The files are read with serde_json here, independently of `handeye::io`.

use std::path::{Path, PathBuf};

use handeye::check::quality::errors_against_truth;
use handeye::model::pose::transform_from_matrix4;
use handeye::solve::{TsaiOptions, tsai_with};
use handeye::{Method, MotionPair, Pairing, PosePair, Setup, Transform, motion_pairs, solve};
use nalgebra::Matrix4;
use serde_json::Value;

/// Largest accepted difference from OpenCV's matrix, entry by entry.
const PARITY: f64 = 1e-6;

/// OpenCV's methods, by the names the fixtures use, and ours.
const SHARED: [(&str, Method); 5] = [
    ("tsai", Method::Tsai),
    ("park", Method::Park),
    ("horaud", Method::Horaud),
    ("andreff-joint", Method::AndreffJoint),
    ("daniilidis", Method::Daniilidis),
];

/// One pose set with OpenCV's answers.
struct Case {
    name: String,
    motions: Vec<MotionPair>,
    /// OpenCV's X per method name.
    opencv: Vec<(String, Transform)>,
    /// Motions OpenCV's Tsai dropped with its motion filter.
    tsai_dropped: usize,
    /// The true X, where the file has it.
    truth: Option<Transform>,
}

impl Case {
    fn opencv(&self, method: &str) -> &Transform {
        &self
            .opencv
            .iter()
            .find(|(name, _)| name == method)
            .unwrap_or_else(|| panic!("{}: no OpenCV answer for {method}", self.name))
            .1
    }
}

/// A 4×4 row-major array, an object with one under `matrix`, or an object with `translation` and
/// `quaternion_xyzw` (kinhec's other form).
fn transform(v: &Value) -> Transform {
    if let Some(q) = v.get("quaternion_xyzw") {
        let number = |a: &Value, i: usize| a[i].as_f64().unwrap_or_else(|| panic!("{v}"));
        let (x, y, z, w) = (number(q, 0), number(q, 1), number(q, 2), number(q, 3));
        let t = &v["translation"];
        #[rustfmt::skip]
        let m = Matrix4::new(
            1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w), number(t, 0),
            2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w), number(t, 1),
            2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y), number(t, 2),
            0.0, 0.0, 0.0, 1.0,
        );
        return transform_from_matrix4(&m).unwrap_or_else(|e| panic!("{e}: {v}"));
    }
    let rows = if v.is_object() { &v["matrix"] } else { v };
    let m = Matrix4::from_fn(|i, j| {
        rows[i][j]
            .as_f64()
            .unwrap_or_else(|| panic!("not a 4×4 matrix: {v}"))
    });
    transform_from_matrix4(&m).unwrap_or_else(|e| panic!("{e}: {v}"))
}

fn setup(v: &Value) -> Setup {
    match v.as_str() {
        Some("eye-in-hand") => Setup::EyeInHand,
        Some("eye-to-hand") => Setup::EyeToHand,
        other => panic!("unknown setup {other:?}"),
    }
}

fn pose_pair(v: &Value) -> PosePair {
    PosePair {
        base_from_gripper: transform(&v["base_from_gripper"]),
        camera_from_target: transform(&v["camera_from_target"]),
    }
}

fn opencv_answers(v: &Value) -> Vec<(String, Transform)> {
    v.as_object()
        .expect("`opencv` is an object")
        .iter()
        .map(|(name, x)| (name.clone(), transform(x)))
        .collect()
}

/// The fixtures of testdata/opencv: NAME.jsonl (one pose pair per line) and NAME.expected.json.
fn fixtures() -> Vec<Case> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/opencv");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("testdata/opencv")
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "jsonl"))
        .collect();
    paths.sort();
    assert_eq!(paths.len(), 4, "fixtures in {}", dir.display());
    paths
        .into_iter()
        .map(|path| {
            let expected: Value = serde_json::from_str(
                &std::fs::read_to_string(path.with_extension("expected.json"))
                    .expect("expected.json"),
            )
            .expect("expected.json is JSON");
            let poses: Vec<PosePair> = std::fs::read_to_string(&path)
                .expect("jsonl")
                .lines()
                .filter(|l| !l.trim().is_empty())
                .map(|l| pose_pair(&serde_json::from_str(l).expect("a JSON line")))
                .collect();
            Case {
                name: path
                    .file_stem()
                    .expect("file name")
                    .to_string_lossy()
                    .into_owned(),
                // Setup::EyeToHand inverts base_from_gripper, as OpenCV's users do for eye-to-hand.
                motions: motion_pairs(&poses, Pairing::All, setup(&expected["setup"])),
                opencv: opencv_answers(&expected["opencv"]),
                tsai_dropped: expected["tsai_filter_dropped_motions"]
                    .as_u64()
                    .expect("tsai_filter_dropped_motions") as usize,
                truth: Some(transform(&expected["truth"])),
            }
        })
        .collect()
}

/// The embedded sets of [`EXTRA`].
fn extra() -> Vec<Case> {
    EXTRA
        .lines()
        .map(|line| {
            let v: Value = serde_json::from_str(line).expect("a JSON line");
            let poses: Vec<PosePair> = v["poses"]
                .as_array()
                .expect("poses")
                .iter()
                .map(pose_pair)
                .collect();
            Case {
                name: v["name"].as_str().expect("name").to_owned(),
                motions: motion_pairs(&poses, Pairing::All, setup(&v["setup"])),
                opencv: opencv_answers(&v["opencv"]),
                tsai_dropped: v["tsai_filter_dropped_motions"]
                    .as_u64()
                    .expect("tsai_filter_dropped_motions") as usize,
                truth: None,
            }
        })
        .collect()
}

fn all_cases() -> Vec<Case> {
    let mut cases = fixtures();
    cases.extend(extra());
    cases
}

fn max_difference(a: &Transform, b: &Transform) -> f64 {
    (a.to_homogeneous() - b.to_homogeneous()).abs().max()
}

#[test]
fn shared_methods_give_opencvs_answer() {
    for case in all_cases() {
        for (name, method) in SHARED {
            // OpenCV 4.14's Tsai always filters; without the filter ours is comparable only
            // where the filter keeps every motion (the filtered form is tested below).
            if method == Method::Tsai && case.tsai_dropped > 0 {
                println!(
                    "{}: tsai without the filter not compared (OpenCV dropped {} motions)",
                    case.name, case.tsai_dropped
                );
                continue;
            }
            // andreff-joint and Daniilidis weigh rotation rows against translation rows: OpenCV
            // in the input's unit, handeye in the data's own RMS length (so that millimetres and
            // metres give one X). On noisy data the answers differ by that weighting (7e-4 here);
            // on exact data they agree, and crates/handeye-py/tests compares them with OpenCV's
            // on the data in units of their RMS length.
            if matches!(method, Method::AndreffJoint | Method::Daniilidis)
                && case.truth.is_none_or(|_| !case.name.contains("exact"))
            {
                println!(
                    "{} {method}: weighted in the data's own unit, not compared",
                    case.name
                );
                continue;
            }
            let ours = solve(method, &case.motions)
                .unwrap_or_else(|e| panic!("{} {method}: {e}", case.name))
                .x;
            let d = max_difference(&ours, case.opencv(name));
            println!("{} {method}: {d:.2e}", case.name);
            assert!(
                d <= PARITY,
                "{} {method}: differs from OpenCV by {d:e}",
                case.name
            );
        }
    }
}

#[test]
fn tsai_with_opencvs_motion_filter_gives_opencvs_answer() {
    let filter = TsaiOptions {
        opencv_filter: true,
    };
    for case in all_cases() {
        let cal = tsai_with(&case.motions, &filter)
            .unwrap_or_else(|e| panic!("{} tsai (filtered): {e}", case.name));
        assert_eq!(
            cal.motions,
            case.motions.len() - case.tsai_dropped,
            "{}: motions kept by the filter",
            case.name
        );
        let d = max_difference(&cal.x, case.opencv("tsai"));
        println!(
            "{} tsai (filtered, {} of {} motions): {d:.2e}",
            case.name,
            cal.motions,
            case.motions.len()
        );
        assert!(d <= PARITY, "{}: differs from OpenCV by {d:e}", case.name);
    }
}

/// kinhec's outlier series (a few flipped, random or grossly wrong poses among 40), on the poses of
/// each that make no motion of more than 170° (testdata/kinhec/opencv_outliers.py chose them and
/// kept the outliers): Park, Horaud and Tsai give OpenCV's answer. Near 180° the sign of a
/// rotation's quaternion or logarithm is in question and handeye takes it from Andreff's R_x;
/// an outlier's motion away from 180° keeps OpenCV's sign. Given the sign that agrees with
/// Andreff's R_x (the rule before), they pulled X towards Andreff's answer, which the outliers
/// move too: up to 0.13 from OpenCV's matrix here, and on the whole series Park and Horaud
/// answered 10–15° from the truth where OpenCV's answer 5–11°.
#[test]
fn outliers_away_from_half_turns_keep_opencvs_signs() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../testdata/kinhec");
    let fixture: Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("opencv_outliers.json")).expect("opencv_outliers.json"),
    )
    .expect("opencv_outliers.json is JSON");
    let series = fixture["series"].as_array().expect("series");
    assert_eq!(
        series.len(),
        18,
        "the outlier series of testdata/kinhec/pairs"
    );
    for s in series {
        let file = s["file"].as_str().expect("file");
        let text = std::fs::read_to_string(dir.join(file)).expect("the series' file");
        let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
        let poses: Vec<PosePair> = s["poses"]
            .as_array()
            .expect("poses")
            .iter()
            .map(|k| {
                let k = k.as_u64().expect("a pose index") as usize;
                pose_pair(&serde_json::from_str(lines[k]).expect("a JSON line"))
            })
            .collect();
        let motions = motion_pairs(&poses, Pairing::All, setup(&s["setup"]));
        let opencv = opencv_answers(&s["opencv"]);
        let answer = |name: &str| &opencv.iter().find(|(n, _)| n == name).expect(name).1;
        let filtered = TsaiOptions {
            opencv_filter: true,
        };
        for (name, ours) in [
            ("park", solve(Method::Park, &motions).map(|c| c.x)),
            ("horaud", solve(Method::Horaud, &motions).map(|c| c.x)),
            ("tsai", tsai_with(&motions, &filtered).map(|c| c.x)),
        ] {
            let ours = ours.unwrap_or_else(|e| panic!("{file} {name}: {e}"));
            let d = max_difference(&ours, answer(name));
            println!("{file} {name} ({} poses): {d:.2e}", poses.len());
            assert!(d <= PARITY, "{file} {name}: differs from OpenCV by {d:e}");
        }
    }
}

/// Rotation error (degrees) and relative translation error against the truth.
fn score(x: &Transform, truth: &Transform) -> (f64, f64) {
    let e = errors_against_truth(x, truth);
    (e.rot_deg, e.trans_rel)
}

/// On one noise draw the OpenCV method with the smallest error changes from measure to measure and
/// set to set, and `andreff-joint` and `daniilidis`, which take rotation information from the
/// translations too, are often well ahead of the rotation-only methods (`tsai`, `park`, `horaud`,
/// and our two-step `andreff`) in rotation. So what is asserted is that `andreff` and `refine` are
/// no worse than 5% above the median OpenCV method on either error; the margins to the best OpenCV
/// method are printed (`cargo test --test opencv_parity -- --nocapture`).
#[test]
fn andreff_and_refine_compared_with_opencvs_methods() {
    for case in fixtures().into_iter().filter(|c| c.name.contains("noisy")) {
        let truth = case.truth.expect("fixtures carry the truth");
        let theirs: Vec<(&str, (f64, f64))> = SHARED
            .iter()
            .map(|(name, _)| (*name, score(case.opencv(name), &truth)))
            .collect();
        for (name, (r, t)) in &theirs {
            println!(
                "{} OpenCV {name:<13}: rotation {r:.4}°, translation {t:.4}",
                case.name
            );
        }
        let best = |k: usize| {
            theirs
                .iter()
                .map(|(name, s)| (*name, if k == 0 { s.0 } else { s.1 }))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .expect("five methods")
        };
        let median = |k: usize| {
            let mut v: Vec<f64> = theirs
                .iter()
                .map(|(_, s)| if k == 0 { s.0 } else { s.1 })
                .collect();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        for method in [Method::Andreff, Method::Refine] {
            let (r, t) = score(&solve(method, &case.motions).expect("solvable").x, &truth);
            let (best_r, best_t) = (best(0), best(1));
            println!(
                "{} ours {method:<9}: rotation {r:.4}° ({:+.4}° vs best OpenCV, {}), translation {t:.4} ({:+.4} vs best OpenCV, {})",
                case.name,
                r - best_r.1,
                best_r.0,
                t - best_t.1,
                best_t.0,
            );
            assert!(
                r <= 1.05 * median(0) && t <= 1.05 * median(1),
                "{} {method}: ({r}, {t}) vs median OpenCV ({}, {})",
                case.name,
                median(0),
                median(1)
            );
        }
    }
}

/// Two pose sets made like OpenCV's calib3d test (10–50° X, 5–45° gripper poses, Gaussian noise
/// of σ 0.002 rad / 0.005 on the camera poses and 0.001 / 0.001 on the robot poses), with the
/// answers of OpenCV 4.14.0's `cv2.calibrateHandEye` (opencv-python-headless 4.14.0.94), one JSON
/// object per line. The first keeps every motion in OpenCV's Tsai filter, so Tsai without the
/// filter is compared too; in the second the filter drops one motion for its camera rotation
/// alone (a filter on the gripper rotation only would keep it and miss OpenCV's answer by 1e-3).
const EXTRA: &str = r#"{"name": "opencv-test-like eye-in-hand, 5 poses, Tsai filter drops nothing", "setup": "eye-in-hand", "tsai_filter_dropped_motions": 0, "poses": [{"base_from_gripper": [[0.8633030960173865, 0.11707632336576415, 0.49091842388929546, 0.8016339215672565], [0.055751613382362925, 0.9446443402121424, -0.32332464816408557, 0.7461746988885953], [-0.5015969716934687, 0.3064966639497423, 0.8089871896239273, 0.7911246112849362], [0.0, 0.0, 0.0, 1.0]], "camera_from_target": [[0.2325422819045389, -0.15621729328284162, -0.9599584597293845, -0.09518419683819297], [0.9334854693025179, -0.24120091477692018, 0.265380853325621, -1.3281389553842144], [-0.27299993723019, -0.9578195424975204, 0.089737162213615, 4.147602322672642], [0.0, 0.0, 0.0, 1.0]]}, {"base_from_gripper": [[0.8668383555178921, -0.4787885549313834, 0.1391142877987524, -0.5480197981938284], [0.4097408318387358, 0.8430538192856011, 0.34838586152721795, -1.2370948803181387], [-0.2840839948450763, -0.24499342328862359, 0.9269706070950599, -1.3068730308136662], [0.0, 0.0, 0.0, 1.0]], "camera_from_target": [[0.3929055752465361, -0.15456148323899577, -0.9064965288621628, 0.1981801959995867], [0.7754538520965767, 0.5855313570554002, 0.23627177819926343, -3.0194182433000423], [0.4942636262246788, -0.7957787241462435, 0.34991383223217665, 4.5061981964135684], [0.0, 0.0, 0.0, 1.0]]}, {"base_from_gripper": [[0.6714119976754834, -0.6051364805495114, -0.42780342364872137, 0.9539087833698234], [0.34633905011118565, 0.7665659031921459, -0.5407642540250707, -1.034261081017086], [0.6551756953256875, 0.21491057668565403, 0.7242639382732937, -1.3893079794528886], [0.0, 0.0, 0.0, 1.0]], "camera_from_target": [[0.751906035386591, -0.6557809566982699, -0.06773958060927482, 2.6995186640340414], [0.5420507035708592, 0.556458501993905, 0.6297102272609487, -1.388417970854935], [-0.3752577097243376, -0.5102012077510214, 0.7738710350580669, 3.7523889917862103], [0.0, 0.0, 0.0, 1.0]]}, {"base_from_gripper": [[0.9308758885945553, -0.19267928190161218, 0.3103945462780818, 1.2813069730867348], [0.13038781102849448, 0.9688803408307881, 0.21040414417689937, -1.0741041774137214], [-0.341275693199054, -0.1553884792302663, 0.9270303780103488, -0.7492726943992192], [0.0, 0.0, 0.0, 1.0]], "camera_from_target": [[0.1928176687741533, -0.23494618572928205, -0.9526917845871049, -0.5149827853436995], [0.9422690831199134, 0.31522507351031226, 0.11296958894665465, -1.4545194250635989], [0.27377056380271914, -0.9194745471418337, 0.28216349082307113, 3.631112930051351], [0.0, 0.0, 0.0, 1.0]]}, {"base_from_gripper": [[0.9631508754736299, -0.25796897264973284, -0.07610781973241479, -0.6356210953983852], [0.2417442533421975, 0.9543427354355409, -0.17546982446401593, 1.0759178684980104], [0.1178987152194789, 0.15060528699700593, 0.9815385578153034, -0.8857553731391131], [0.0, 0.0, 0.0, 1.0]], "camera_from_target": [[0.5004401265983734, -0.5552457503548853, -0.6642754220976752, 1.7504855143291853], [0.8642290197051004, 0.2746013476533437, 0.4215475078404909, -3.253264247896649], [-0.051651536180109925, -0.7850453850445895, 0.6172810237083487, 5.072913651728118], [0.0, 0.0, 0.0, 1.0]]}], "opencv": {"tsai": [[0.951308516881973, -0.12259940599255557, 0.2828099916164441, -0.1390186128905928], [0.1827717383458004, 0.963161421030249, -0.19726775889902928, -0.255089477419919], [-0.2482067633443435, 0.23935217293616493, 0.9386713695116418, 0.2232841226885074], [0.0, 0.0, 0.0, 1.0]], "park": [[0.9513083251768839, -0.12260506110556246, 0.2828081848894213, -0.13901716299315955], [0.18276116396815234, 0.9631756896375454, -0.19720787975188925, -0.25514756162243923], [-0.24821528436854257, 0.23929185084855487, 0.9386844958362195, 0.2232740511306474], [0.0, 0.0, 0.0, 1.0]], "horaud": [[0.9513107975366137, -0.12261692558057734, 0.28279472422840435, -0.13902191817641502], [0.18278617808014236, 0.9631581823696184, -0.19727019247039695, -0.25510695821014756], [-0.2481873880621386, 0.23935623095215242, 0.9386754578187678, 0.2232643479497921], [0.0, 0.0, 0.0, 1.0]], "andreff-joint": [[0.9520618841811774, -0.11934170734463499, 0.28166598228656153, -0.12993824570485002], [0.1797017099751595, 0.9633313602689177, -0.19924855270350147, -0.262636198748028], [-0.2475590113920107, 0.24031281116599618, 0.9385969788296286, 0.2277183522116823], [0.0, 0.0, 0.0, 1.0]], "daniilidis": [[0.9528552173613439, -0.11732289801998216, 0.27982543191686304, -0.13950803610378051], [0.17736074221190654, 0.9636252299097849, -0.1999239440471193, -0.24983293919893068], [-0.24619118966629924, 0.24012861945529715, 0.9390038041718389, 0.22485525345440327], [0.0, 0.0, 0.0, 1.0]]}}
{"name": "opencv-test-like eye-to-hand, 4 poses, Tsai filter drops one motion for its camera rotation only", "setup": "eye-to-hand", "tsai_filter_dropped_motions": 1, "poses": [{"base_from_gripper": [[0.9015722500084425, 0.01842199779709903, -0.43223617156813476, -0.6059226157043526], [0.03983847527491732, 0.9913128608225961, 0.12534635158428029, 0.7473543561492582], [0.4307904060009742, -0.13022842226213097, 0.8930062620903797, 0.8905975485275822], [0.0, 0.0, 0.0, 1.0]], "camera_from_target": [[0.7928507613750393, 0.07721034831016536, -0.6045049481194041, -4.963540098713485], [0.31342729522484075, 0.7990321932919789, 0.5131382705383123, 0.925279518782875], [0.5226384991512404, -0.5963104193260693, 0.60931345218049, 2.3640328958404475], [0.0, 0.0, 0.0, 1.0]]}, {"base_from_gripper": [[0.9828945107469865, 0.09888361215041917, -0.15537185070509865, 0.6855069004207798], [-0.07755657112622473, 0.9874194379149666, 0.1377963421242901, -1.2043605486546793], [0.16704298554140137, -0.12338916028475529, 0.9781982192304575, -1.2400838194048116], [0.0, 0.0, 0.0, 1.0]], "camera_from_target": [[0.9052283051328696, 0.010290088438718856, -0.42480092945542836, -3.599521333427996], [0.17627549071022403, 0.9005344496506036, 0.39744767752165105, -1.7670393023987432], [0.3866376429696702, -0.43466287979583434, 0.8133753831819905, 1.55729226226043], [0.0, 0.0, 0.0, 1.0]]}, {"base_from_gripper": [[0.8089148342624876, -0.48724554500603073, 0.3290115040266349, -1.3883058029335589], [0.23344427158678566, 0.7797967770998612, 0.5808792976927173, -1.0076972769660688], [-0.5395929604557563, -0.3930760299184439, 0.7445338620439954, 0.8279123454744486], [0.0, 0.0, 0.0, 1.0]], "camera_from_target": [[0.7940345768091235, -0.570807823316727, 0.2090155967194228, -2.782871231721719], [0.3981165321042256, 0.7481720116887368, 0.5307936207142411, -0.3377260134656675], [-0.4593607707421926, -0.33825592347518285, 0.8213224777985136, 4.73822588622594], [0.0, 0.0, 0.0, 1.0]]}, {"base_from_gripper": [[0.8959347909652469, 0.34544263755415616, -0.2792315069931891, -0.9935656040732028], [-0.1816472362276718, 0.8586077178794351, 0.47937153479187383, -0.9712788665831543], [0.4053456943263465, -0.3787640043054464, 0.8320052266263691, 0.9311138901257526], [0.0, 0.0, 0.0, 1.0]], "camera_from_target": [[0.9076398165277475, 0.3288842597267681, -0.260816232542096, -5.7843245801399386], [-0.05345986712098438, 0.7068749009367327, 0.7053154734110765, 1.3954836844854994], [0.4163316058875229, -0.6262292057463146, 0.6591699142174621, 2.5286697693166875], [0.0, 0.0, 0.0, 1.0]]}], "opencv": {"tsai": [[0.7511496468302998, -0.47859272159070443, 0.4546682470847492, 0.256506234175941], [0.4772445527467233, 0.8695637211135088, 0.1268722656722421, -0.42217278677750575], [-0.456083155729628, 0.12168788667583316, 0.8815782513742461, -0.5140600763832319], [0.0, 0.0, 0.0, 1.0]], "park": [[0.7509340458675619, -0.47857698306390595, 0.45504080041071526, 0.25530265178868494], [0.4770525881747638, 0.8696032100424622, 0.12732275994339015, -0.42197009657351225], [-0.4566386830665253, 0.12146739630573489, 0.8813210452281119, -0.5137045058667558], [0.0, 0.0, 0.0, 1.0]], "horaud": [[0.7509310008413221, -0.47857522417052967, 0.45504767528862045, 0.25527251515838545], [0.47703119464878285, 0.8696091653721567, 0.1273622347193086, -0.422038068378201], [-0.4566660391439301, 0.12143168577792413, 0.8813117918090771, -0.5137204524281697], [0.0, 0.0, 0.0, 1.0]], "andreff-joint": [[0.758747297617651, -0.4743107697793133, 0.44646593602341855, 0.2727452225107894], [0.4725987546406385, 0.872539075139781, 0.1237981399954527, -0.40338546213177406], [-0.44827776597778074, 0.11706774118249322, 0.8861953444384595, -0.49463669797291276], [0.0, 0.0, 0.0, 1.0]], "daniilidis": [[0.7592557366032997, -0.47298830481403986, 0.44700423929099553, 0.27263953290936105], [0.47084605773154997, 0.8733982926408821, 0.12441628643650333, -0.41465285846822947], [-0.4492601878128515, 0.11600640465566121, 0.8858373427019366, -0.5005772541382769], [0.0, 0.0, 0.0, 1.0]]}}"#;
