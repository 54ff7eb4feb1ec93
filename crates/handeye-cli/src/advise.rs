//! `handeye advise`: what to record next, from the poses recorded so far.

use anyhow::Result;
use clap::Args as ClapArgs;
use handeye::{Advice, AdviseOptions, Part, Pivot, Unit, advise};

use crate::faces::{self, short};
use crate::input::{InputArgs, read_all};
use crate::output::print_json;

/// Options of `handeye advise`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    input: InputArgs,
    /// How many next motions to suggest (1 to 20).
    #[arg(long, default_value_t = 3, value_parser = crate::values::count(1, 20))]
    count: usize,
    /// A prior on a component of X's translation, for a low-DOF robot (as `calibrate --prior`):
    /// NAME=VALUE or NAME=VALUE+-SIGMA, NAME one of tx, ty, tz. The advice is then for that
    /// robot: turns about its one axis. Repeatable.
    #[arg(long, value_name = "NAME=VALUE[+-SIGMA]", value_parser = crate::values::prior)]
    prior: Vec<handeye::Prior>,
    /// The one-sigma X you need, rotation in degrees and translation in the input's unit (e.g.
    /// `0.1,0.001` for 0.1° and 1 mm in metres): the advice says when you are done, or after
    /// which suggested motion the prediction is within it.
    #[arg(long, value_name = "DEGREES,LENGTH", value_parser = crate::values::goal)]
    goal: Option<handeye::Sizes>,
}

/// Runs the command: the advice as JSON on stdout, in words on stderr.
pub fn run(args: Args) -> Result<()> {
    let recording = read_all(&args.input, handeye::Reading::AsGiven)?;
    let options = AdviseOptions {
        count: args.count,
        priors: args.prior,
        goal: args.goal,
    };
    let advice = recording.offset_checked(advise(
        &recording.poses,
        args.input.setup(),
        recording.written,
        &options,
    ))?;
    let poses = recording.poses;
    eprint!(
        "{}",
        crate::output::escaped_text(&in_words(&advice, faces::length_unit(&poses)))
    );
    print_json(&advice)
}

/// The advice in a few lines, lengths in the input's unit.
fn in_words(advice: &Advice, unit: Option<Unit>) -> String {
    let u = faces::unit_name(unit);
    let mut out = String::new();
    if let Some(words) = &advice.low_dof {
        out.push_str(&format!("{words}\n"));
    }
    match advice.current {
        Some(c) => out.push_str(&format!(
            "X from {} poses{}: one-sigma {:.3}° and {} {u}\n",
            advice.poses,
            if advice.outliers > 0 {
                format!(" ({} outlier(s) left out)", advice.outliers)
            } else {
                String::new()
            },
            c.rotation_deg,
            short(c.translation)
        )),
        None => out.push_str(&format!(
            "X is not determined by these {} poses: every rotation so far is about one axis\n",
            advice.poses
        )),
    }
    for w in &advice.weakest {
        let [x, y, z] = w.axis_gripper;
        out.push_str(&match w.kind {
            Part::Rotation => format!(
                "  weakest rotation: about the gripper axis ({x:.2}, {y:.2}, {z:.2}), sigma {:.3}°\n",
                w.sigma
            ),
            Part::Translation => format!(
                "  weakest translation: along ({x:.2}, {y:.2}, {z:.2}), sigma {} {u}\n",
                short(w.sigma)
            ),
        });
    }
    for (k, s) in advice.suggestions.iter().enumerate() {
        let [x, y, z] = s.axis_gripper;
        let pivot = match s.pivot {
            Pivot::Flange => {
                "through the flange (the gripper frame's origin stays put; keep the target in view)"
                    .to_string()
            }
            Pivot::Target => {
                let [px, py, pz] = s.pivot_gripper.map(short);
                format!(
                    "through the target, at ({px}, {py}, {pz}) {u} in the gripper frame (it stays where the camera sees it)"
                )
            }
        };
        out.push_str(&format!(
            "next motion {}: turn the gripper {:.0}° about its axis ({x:.2}, {y:.2}, {z:.2}) {pivot}",
            k + 1,
            s.angle_deg
        ));
        match s.predicted {
            Some(p) => out.push_str(&format!(
                " -> sigma {:.3}° and {} {u}\n",
                p.rotation_deg,
                short(p.translation)
            )),
            None => out.push('\n'),
        }
    }
    if let Some(g) = &advice.goal {
        let goal = format!(
            "{:.3}° and {} {u}",
            g.goal.rotation_deg,
            short(g.goal.translation)
        );
        out.push_str(&match (g.done, g.after) {
            (true, _) => format!(
                "you are done: X is within your goal ({goal}, one sigma); more poses are not needed for it\n"
            ),
            (false, Some(k)) => format!(
                "your goal ({goal}, one sigma) is predicted after next motion {k}\n"
            ),
            (false, None) => format!(
                "your goal ({goal}, one sigma) is not reached by the motions suggested: record them, then ask again\n"
            ),
        });
    }
    out
}
