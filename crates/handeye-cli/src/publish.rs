//! What the ROS faces publish when a recording's tf gives the camera frame a parent already (an
//! optical frame under `camera_link`): tf gives a frame one parent, so X is published for the
//! root of the camera's subtree, `parent_from_root = X · camera_from_root`; or, when that root
//! hangs in the robot's tree (the camera was calibrated before), not beside it: X is compared with
//! tf's. The facts are the library's ([`CameraMount`]); this words them.

use handeye::io::CameraMount;
use handeye::{Transform, TransformJson};

use crate::faces::{self, Frames, Published};

/// X as the ROS faces publish it, for its frames, and what to tell about it.
#[derive(Debug, Clone)]
pub struct Publication {
    /// The transform published: X, or X carried to the frame published.
    pub x: Transform,
    /// Its frames.
    pub frames: Frames,
    /// Why it is not X for the frames asked (X carried to the root of the camera's subtree).
    pub note: Option<String>,
    /// What it is then, in a formula: `tool0_from_camera_link = X · optical_from_camera_link`.
    pub formula: Option<String>,
    /// What publishing it as it is breaks in the recording's tf.
    pub warning: Option<String>,
    /// What stderr says in place of the publish line when nothing is offered, beyond the
    /// reading's note: X against the transform tf has (the camera placed in the robot's tf
    /// already), or why the frame to publish for cannot be named.
    pub instead: Option<String>,
    /// Whether it is offered for publishing: not when the camera is placed in the robot's tf
    /// already, nor when its chain moves (unless `--child-frame` names the frame).
    pub offered: bool,
}

impl Publication {
    /// `p` with this transform and its comments.
    pub fn of<'a>(&'a self, p: Published<'a>) -> Published<'a> {
        Published {
            x: &self.x,
            note: self.note.as_deref(),
            warning: self.warning.as_deref(),
            ..p
        }
    }

    /// On stderr, after a result from a recording: the publish line (when `line`), with its
    /// note, or what stands in its place.
    pub fn tell(&self, p: Published<'_>, line: bool) {
        if !self.offered {
            if let Some(instead) = &self.instead {
                crate::tell!("{instead}");
            }
            return;
        }
        if let Some(warning) = &self.warning {
            crate::tell!("warning: {warning}");
        }
        if !line {
            return;
        }
        let command = faces::static_transform_publisher(self.of(p), &self.frames);
        match &self.formula {
            Some(formula) => crate::tell!("publish {formula} in tf with: {command}"),
            None => crate::tell!("publish X in tf with: {command}"),
        }
    }

    /// The JSON report's `publish`: the frames, the transform offered, the note and the warning;
    /// none when there is nothing to say beyond X.
    pub fn json(&self) -> Option<serde_json::Value> {
        if self.note.is_none() && self.warning.is_none() {
            return None;
        }
        let mut v = serde_json::json!({
            "parent_frame": self.frames.parent,
            "child_frame": self.frames.child,
        });
        if self.offered
            && let Ok(serde_json::Value::Object(t)) =
                serde_json::to_value(TransformJson::from(&self.x))
        {
            v.as_object_mut()?.extend(t);
        }
        for (key, text) in [("note", &self.note), ("warning", &self.warning)] {
            if let Some(text) = text {
                v[key] = text.as_str().into();
            }
        }
        Some(v)
    }
}

/// What the ROS faces publish for X (`parent_from_camera` between `frames`), given where the
/// recording's tf places the camera frame (`mount`) and whether `--child-frame` named the frame.
pub fn publication(
    x: &Transform,
    frames: &Frames,
    mount: Option<&CameraMount>,
    child_given: bool,
) -> Publication {
    let asked = Publication {
        x: *x,
        frames: frames.clone(),
        note: None,
        formula: None,
        warning: None,
        instead: None,
        offered: true,
    };
    match mount {
        None => asked,
        Some(mount) if child_given => given_child(asked, mount),
        Some(mount) if mount.placed_under.is_some() => placed(asked, mount),
        Some(mount) => carried(asked, mount),
    }
}

/// A frame name from the recording's tf when it is a ROS name, as the flags' must be (it is
/// printed into shell, YAML, XML and Python).
fn recorded(name: &str) -> Option<String> {
    faces::frame_name("camera_frame", name).ok()
}

/// Nothing offered: a frame of the camera's chain has a name no ROS frame may have, so the
/// transform to publish cannot be named (the name itself is not printed into the faces).
fn unnamed(asked: Publication) -> Publication {
    let camera = &asked.frames.child;
    let warning = format!(
        "`{camera}` has a parent in the recording's tf, and a frame above it has a name no ROS frame may have (a letter or `_` first, then letters, digits, `_`, `/`, `.`, `-`; `handeye inspect` lists them): publishing X for `{camera}` gives it a second parent, and the frame to publish it for cannot be named here; name it with --child-frame"
    );
    Publication {
        warning: Some(warning.clone()),
        instead: Some(format!("warning: {warning}")),
        offered: false,
        ..asked
    }
}

/// The camera frame's own parent in the recording's tf (the first frame above it).
fn camera_parent(mount: &CameraMount) -> Option<&str> {
    mount
        .above
        .first()
        .map(|f| f.frame.as_str())
        .or(mount.placed_under.as_deref())
}

/// No `--child-frame`, the camera's subtree apart from the robot's tree: X carried to its root,
/// or, when a transform of the chain moves, nothing offered.
fn carried(asked: Publication, mount: &CameraMount) -> Publication {
    let names = (
        recorded(mount.root()),
        camera_parent(mount).and_then(recorded),
    );
    let (Some(root), Some(parent)) = names else {
        return unnamed(asked);
    };
    let (p, camera) = (&asked.frames.parent, &asked.frames.child);
    let Some(root_from_camera) = mount.frame_from_camera(mount.root()) else {
        let warning = format!(
            "`{camera}` has a parent in the recording's tf already (`{parent}`): publishing X for it gives it a second parent (tf allows one); and a transform between it and `{root}`, the root of the camera's subtree, is in /tf (it moves), so no static transform for `{root}` can be offered"
        );
        return Publication {
            warning: Some(warning),
            offered: false,
            ..asked
        };
    };
    let formula = format!("{p}_from_{root} = X · {camera}_from_{root}");
    let note = format!(
        "X is published for `{root}`, the root of the camera's subtree, not for `{camera}`: tf gives a frame one parent, and the recording's /tf_static gives `{camera}` one already (`{parent}`); {formula}, and X itself stays {p}_from_{camera}"
    );
    Publication {
        x: asked.x * root_from_camera.inverse(),
        frames: Frames {
            child: root,
            ..asked.frames.clone()
        },
        note: Some(note),
        formula: Some(formula),
        ..asked
    }
}

/// No `--child-frame`, the camera placed in the robot's tf already: nothing offered, X compared
/// with tf's.
fn placed(asked: Publication, mount: &CameraMount) -> Publication {
    let under = mount.placed_under.as_deref().and_then(recorded);
    let names = (recorded(mount.root()), under, recorded(&mount.x_parent));
    let (Some(root), Some(under), Some(parent)) = names else {
        return unnamed(asked);
    };
    let camera = &asked.frames.child;
    let compared = mount.tf_x.map(|tf_x| {
        let x_from_tf = asked.x.inverse() * tf_x;
        format!(
            "tf's {parent}_from_{camera} (the calibration the recording has) is {:.4}° and {:.3} mm from X",
            x_from_tf.rotation.angle().to_degrees(),
            x_from_tf.translation.vector.norm() * 1e3
        )
    });
    let warning = format!(
        "the recording's tf places `{root}` under `{under}` already (the camera was calibrated before): X published beside that transform would give `{root}` a second parent or close a loop (tf allows one parent); compare X with tf's instead{}, or check the calibration tf has with `handeye verify --x SAVED` on a recording",
        compared
            .as_ref()
            .map_or(String::new(), |c| format!(" ({c})"))
    );
    Publication {
        warning: Some(warning),
        instead: compared,
        offered: false,
        ..asked
    }
}

/// `--child-frame` given: published for the frame named. Carried to it when it is above the
/// camera frame through static transforms; a warning when the recording's tf gives it a parent.
fn given_child(asked: Publication, mount: &CameraMount) -> Publication {
    let child = asked.frames.child.clone();
    let camera = mount.camera.as_str();
    let in_chain = child == camera || mount.above.iter().any(|f| f.frame == child);
    if !in_chain {
        // A frame the recording's camera chain does not hold (its name on the robot, say).
        return asked;
    }
    let p = asked.frames.parent.clone();
    let has_parent = chain_parent(mount, &child).map(|parent| {
        let parent = recorded(parent).map_or(String::new(), |name| format!(" (`{name}`)"));
        format!(
            "`{child}` has a parent in the recording's tf already{parent}: publishing X for it gives it a second parent (tf allows one)"
        )
    });
    let Some(child_from_camera) = mount.frame_from_camera(&child) else {
        let moving = format!(
            "a transform between `{camera}` and `{child}` is in the recording's /tf (it moves): X is `{camera}`'s, published under the name `{child}`"
        );
        let warning = has_parent.map_or(moving.clone(), |h| format!("{h}; {moving}"));
        return Publication {
            warning: Some(warning),
            ..asked
        };
    };
    let formula =
        (child != camera).then(|| format!("{p}_from_{child} = X · {camera}_from_{child}"));
    let note = formula.as_ref().map(|formula| {
        format!(
            "X is published for `{child}` (--child-frame), above `{camera}` in the recording's tf: {formula}, from its /tf_static"
        )
    });
    Publication {
        x: asked.x * child_from_camera.inverse(),
        note,
        formula,
        warning: has_parent,
        ..asked
    }
}

/// The parent the recording's tf gives `frame`, the camera frame or a frame above it.
fn chain_parent<'a>(mount: &'a CameraMount, frame: &str) -> Option<&'a str> {
    if frame == mount.camera {
        return camera_parent(mount);
    }
    let k = mount.above.iter().position(|f| f.frame == frame)?;
    mount
        .above
        .get(k + 1)
        .map(|f| f.frame.as_str())
        .or(mount.placed_under.as_deref())
}
