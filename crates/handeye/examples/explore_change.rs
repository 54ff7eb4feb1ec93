use handeye::sync::{TimeOffset, pair_stream_files};
use handeye::tracking::{TrackOptions, Tracker};
use handeye::{Method, Pairing, Setup, motion_pairs, solve};
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args[1] == "sim" { return sim(); }
    if args[1] == "dbg" { let r: f64 = args[2].parse().unwrap(); let t: f64 = args[3].parse().unwrap(); for s in 0..40 { println!("seed {s}"); debug_seed(r, t, s); } return; }
    let setup = if args.get(3).map(|s| s.as_str()) == Some("eth") { Setup::EyeToHand } else { Setup::EyeInHand };
    let p = pair_stream_files(Path::new(&args[1]), Path::new(&args[2]), setup, TimeOffset::Auto, 0.1).unwrap();
    let poses = p.synced.pairs;
    let batch = solve(Method::Andreff, &motion_pairs(&poses, Pairing::All, setup)).unwrap().x;
    let mut t = Tracker::new(setup, TrackOptions::default());
    let (mut reports, mut screw, mut resid) = (0, 0, 0);
    let bad: Vec<f64> = std::env::var("BAD_LINES").ok().map(|v| { let text = std::fs::read_to_string(&args[2]).unwrap(); let lines: Vec<&str> = text.lines().collect(); v.split(',').map(|l| lines[l.parse::<usize>().unwrap()-1].split_whitespace().next().unwrap().parse::<f64>().unwrap()).collect() }).unwrap_or_default();
    let (mut hit, mut miss, mut extra) = (0, 0, 0);
    let mut ests = vec![];
    for (k, q) in poses.iter().enumerate() {
        let s = t.push(q);
        let is_bad = bad.iter().any(|b| (b - p.synced.stamps[k]).abs() < 1e-6);
        match (is_bad, s.held_out.is_some()) { (true, true) => hit += 1, (true, false) => { miss += 1; if std::env::var("SHOW").is_ok() { println!("missed pose {}", k+1) } }, (false, true) => extra += 1, _ => {} }
        if let Some(c) = s.change { println!("CHANGE at {} confirmed {} dx {:.2}° {:.4} dy {:.2}° {:.4}", c.at, c.confirmed, c.x_rotation_deg, c.x_translation, c.target_rotation_deg, c.target_translation); }
        if let Some(r) = s.report { reports += 1; ests.push(r.estimate); }
        match s.held_out { Some(handeye::tracking::HeldOut::Screw{..}) => screw += 1, Some(_) => resid += 1, None => {} }
    }
    if !bad.is_empty() { println!("planted {} held {hit} missed {miss} good held {extra}", bad.len()); }
    let fin = t.finish();
    let e = t.estimate().unwrap();
    let d = batch.inverse() * e.x;
    println!("n {} reports {reports} (+end {}) held out screw {screw} resid {resid}; final vs batch {:.3}° {:.2} mm; unc {:?} {:?} pending {:?}", poses.len(), fin.is_some(), d.rotation.angle().to_degrees(), 1e3*d.translation.vector.norm(), e.uncertainty_rotation_deg, e.uncertainty_translation, t.pending());
    let reference = match args.get(4) { Some(t) => handeye::io::read_truth(Path::new(t)).unwrap().x, None => e.x };
    for r in &ests { let d = reference.inverse() * r.x; println!("   report at {} poses: err {:.3}° {:.1} mm  sigma {:.3}° {:.1} mm  ratio {:.2} {:.2}", r.poses, d.rotation.angle().to_degrees(), 1e3*d.translation.vector.norm(), r.uncertainty_rotation_deg.unwrap(), 1e3*r.uncertainty_translation.unwrap(), d.rotation.angle().to_degrees()/r.uncertainty_rotation_deg.unwrap(), d.translation.vector.norm()/r.uncertainty_translation.unwrap()); }
    if let Some(truth) = args.get(4) {
        let tr = handeye::io::read_truth(Path::new(truth)).unwrap().x;
        let d = tr.inverse() * e.x; let db = tr.inverse() * batch;
        println!("   vs truth: tracker {:.3}° {:.2} mm, batch {:.3}° {:.2} mm", d.rotation.angle().to_degrees(), 1e3*d.translation.vector.norm(), db.rotation.angle().to_degrees(), 1e3*db.translation.vector.norm());
    }
}

fn sim() {
    use handeye::sim::{Jump, SimConfig, simulate};
    for (rot, tr) in [(0.25, 1.25), (0.1, 0.5), (1.0, 5.0), (10.0, 50.0)] {
        let mut delays = vec![]; let mut false_alarms = 0; let mut missed = 0;
        for seed in 0..40 {
            let sim = simulate(&SimConfig { poses: 300, jump: Some(Jump { at: 120, rotation_deg: rot, translation: tr }), ..SimConfig::default() }, 5, seed);
            let mut t = Tracker::new(Setup::EyeInHand, TrackOptions::default());
            let mut first = None;
            for q in &sim.poses { let s = t.push(q); if let Some(c) = s.change { if c.confirmed < 120 || c.at < 115 { false_alarms += 1 } else { first.get_or_insert(c.confirmed); } } }
            match first { Some(f) if f < 150 => delays.push(f - 120), _ => missed += 1 }
        }
        delays.sort();
        println!("jump {rot}°/{tr}: detected {} missed {missed} false {false_alarms} median delay {:?}", delays.len(), delays.get(delays.len()/2));
    }
    let mut alarms = 0;
    for seed in 0..30 { let sim = simulate(&SimConfig { poses: 1000, ..SimConfig::default() }, 77, seed); let mut t = Tracker::new(Setup::EyeInHand, TrackOptions::default()); for q in &sim.poses { if t.push(q).change.is_some() { alarms += 1 } } }
    println!("stationary: {alarms} alarms in 30000 poses");
}
#[allow(dead_code)]
pub fn debug_seed(rot: f64, tr: f64, seed: u64) {
    use handeye::sim::{Jump, SimConfig, simulate};
    let sim = simulate(&SimConfig { poses: 300, jump: Some(Jump { at: 120, rotation_deg: rot, translation: tr }), ..SimConfig::default() }, 5, seed);
    let mut t = Tracker::new(Setup::EyeInHand, TrackOptions::default());
    for (k, q) in sim.poses.iter().enumerate() { let s = t.push(q); if k >= 110 && k < 160 { println!("{} held {:?} change {:?} {:?}", s.pose, s.held_out.map(|_| 1), s.change.map(|c| (c.at, c.confirmed)), t.pending().map(|_| "pending")); } }
}
