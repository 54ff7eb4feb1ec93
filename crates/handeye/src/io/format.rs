//! The pose-file formats as one table ([`FORMATS`]): each format's extensions, how its content
//! is told from the head of a file, and how it is read (record by record, whole, or as a
//! directory). Every place that decides something by format reads this table; adding a format is
//! one reader file and one row here (docs/ARCHITECTURE.md, "Adding an input format").

use std::path::Path;

use super::peer;
use super::series::PoseSeries;
use crate::model::error::Result;

/// Pose-pair file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Format {
    /// By extension (`.jsonl`/`.json`, `.csv`), else by content (`{` first: JSON Lines).
    #[default]
    Auto,
    /// One JSON object per line.
    Jsonl,
    /// CSV with a header naming `<frame>_x … <frame>_qw` columns.
    Csv,
    /// OpenCV-YAML pairs `T1_i` / `T2_i` (camodocal).
    OpencvYaml,
    /// moveit_calibration's sample JSON (a list of matrix pairs).
    Moveit,
    /// A directory of ViSP `pose_fPe_*.yaml` / `pose_cPo_*.yaml` files.
    Visp,
    /// moveit_calibration's "Save samples" YAML (`effector_wrt_world` / `object_wrt_sensor`).
    MoveitYaml,
    /// easy_handeye2's saved samples (`NAME.samples`: `parameters` and `samples`).
    EasyHandeye,
}

crate::named_enum!(Format, "format", "format" {
    Auto => "auto",
    Jsonl => "jsonl" | "json",
    Csv => "csv",
    OpencvYaml => "opencv-yaml" | "yaml",
    Moveit => "moveit",
    Visp => "visp",
    MoveitYaml => "moveit-yaml",
    EasyHandeye => "easy-handeye",
});

/// A reader of a whole text, named `source` in messages.
pub(crate) type WholeReader = fn(&str, &str) -> Result<PoseSeries>;

/// A reader of a directory of files.
pub(crate) type DirectoryReader = fn(&Path) -> Result<PoseSeries>;

/// How a format is read.
#[derive(Clone, Copy)]
pub(crate) enum Reading {
    /// Told per record and read one line at a time (`PoseReader`): a stream, a pipe, `-`.
    Streamed,
    /// Read whole, from a file or a pipe: `reader(text, source)`.
    Whole(WholeReader),
    /// A directory of files: `reader(dir)`.
    Directory(DirectoryReader),
}

/// What the head of a file's content shows, for the formats told by content
/// ([`Row::sniff`]).
pub(crate) struct Head<'a> {
    /// The head as text (invalid UTF-8 replaced).
    pub text: &'a str,
    /// The same without a byte order mark and leading white space.
    pub trimmed: &'a str,
}

/// One format's row of [`FORMATS`].
pub(crate) struct Row {
    /// The format.
    pub format: Format,
    /// File-name endings (lower case) that name it when the format is `auto`.
    pub extensions: &'static [&'static str],
    /// Whether the head of a file's content is of this format (tried in the table's order;
    /// `None`: not told by content here — JSON Lines and CSV are told line by line by the
    /// streaming reader, ViSP by being a directory).
    pub sniff: Option<fn(&Head) -> bool>,
    /// How it is read.
    pub reading: Reading,
    /// The format in words, for the refusal of a rotation convention named for a format that
    /// writes its rotations one way only (`None`: the format's rotations may be named).
    pub own_rotations: Option<&'static str>,
}

/// Every format but `auto`, in the order their content is tried.
pub(crate) const FORMATS: &[Row] = &[
    Row {
        format: Format::Jsonl,
        extensions: &[".jsonl", ".json", ".ndjson"],
        sniff: None,
        reading: Reading::Streamed,
        own_rotations: None,
    },
    Row {
        format: Format::Csv,
        extensions: &[".csv"],
        sniff: None,
        reading: Reading::Streamed,
        own_rotations: None,
    },
    Row {
        format: Format::OpencvYaml,
        extensions: &[],
        sniff: Some(|h| h.trimmed.starts_with("%YAML") || h.text.contains("!!opencv-matrix")),
        reading: Reading::Whole(peer::read_opencv_yaml),
        own_rotations: Some("an OpenCV YAML file of matrices"),
    },
    Row {
        format: Format::Moveit,
        extensions: &[],
        // A JSON list (not a log line such as `[INFO] driver started`).
        sniff: Some(|h| {
            h.trimmed.strip_prefix('[').is_some_and(|rest| {
                matches!(
                    rest.trim_start().chars().next(),
                    None | Some('[' | '{' | ']')
                )
            })
        }),
        reading: Reading::Whole(peer::read_moveit_json),
        own_rotations: Some("a moveit_calibration sample file of matrices"),
    },
    Row {
        format: Format::Visp,
        extensions: &[],
        sniff: None,
        reading: Reading::Directory(peer::read_visp_dir),
        own_rotations: Some("a directory of ViSP pose files (θu rotation vectors)"),
    },
    Row {
        format: Format::MoveitYaml,
        extensions: &[],
        sniff: Some(|h| {
            h.text.contains("effector_wrt_world:") || h.text.contains("object_wrt_sensor:")
        }),
        reading: Reading::Whole(peer::read_moveit_yaml),
        own_rotations: Some("a moveit_calibration sample file of matrices"),
    },
    Row {
        format: Format::EasyHandeye,
        extensions: &[],
        sniff: Some(|h| {
            h.text
                .lines()
                .map(|l| l.trim_start_matches('\u{feff}').trim_end())
                .find(|l| {
                    !l.trim_start().is_empty() && !l.trim_start().starts_with('#') && *l != "---"
                })
                .is_some_and(|l| l == "parameters:" || l == "samples:")
        }),
        reading: Reading::Whole(peer::read_easy_handeye_samples),
        own_rotations: Some("an easy_handeye2 sample file (x, y, z, w quaternions)"),
    },
];

impl Format {
    /// This format's row of [`FORMATS`] (`None` for `auto`).
    pub(crate) fn row(self) -> Option<&'static Row> {
        FORMATS.iter().find(|r| r.format == self)
    }

    /// How this format is read (`auto`: streamed, until the content says otherwise).
    pub(crate) fn reading(self) -> Reading {
        self.row().map_or(Reading::Streamed, |r| r.reading)
    }

    /// Whether it is read record by record (JSON Lines, CSV; `auto` until told).
    pub(crate) fn is_streamed(self) -> bool {
        matches!(self.reading(), Reading::Streamed)
    }

    /// The streamed format a file name names by its ending (`auto` when none does).
    pub(crate) fn by_extension(source: &str) -> Format {
        let lower = source.to_ascii_lowercase();
        FORMATS
            .iter()
            .filter(|r| matches!(r.reading, Reading::Streamed))
            .find(|r| r.extensions.iter().any(|e| lower.ends_with(e)))
            .map_or(Format::Auto, |r| r.format)
    }

    /// The format the head of a file's content shows, of those told by content; `auto` (told per
    /// record) otherwise.
    pub(crate) fn sniffed(head: &Head) -> Format {
        FORMATS
            .iter()
            .find(|r| r.sniff.is_some_and(|sniff| sniff(head)))
            .map_or(Format::Auto, |r| r.format)
    }

    /// The reader of `path` as a directory, and the format in words: this format's when it is
    /// read so, or with `auto` the directory format's when `path` is a directory.
    pub(crate) fn directory(self, path: &Path) -> Option<(DirectoryReader, &'static str)> {
        let of = |r: &Row| match (r.reading, r.own_rotations) {
            (Reading::Directory(read), Some(what)) => Some((read, what)),
            _ => None,
        };
        match self {
            Format::Auto if path.is_dir() => FORMATS.iter().find_map(of),
            Format::Auto => None,
            f => f.row().and_then(of),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_format_but_auto_has_one_row() {
        for format in Format::ALL {
            let rows = FORMATS.iter().filter(|r| r.format == format).count();
            assert_eq!(rows, usize::from(format != Format::Auto), "{format:?}");
        }
    }

    #[test]
    fn extensions_name_the_streamed_formats() {
        assert_eq!(Format::by_extension("a/B.JSONL"), Format::Jsonl);
        assert_eq!(Format::by_extension("x.ndjson"), Format::Jsonl);
        assert_eq!(Format::by_extension("x.csv"), Format::Csv);
        assert_eq!(Format::by_extension("x.yaml"), Format::Auto);
        assert_eq!(Format::by_extension("-"), Format::Auto);
    }

    #[test]
    fn the_head_tells_the_formats_read_whole() {
        let sniff = |text: &str| {
            Format::sniffed(&Head {
                text,
                trimmed: text.trim_start_matches('\u{feff}').trim_start(),
            })
        };
        assert_eq!(sniff("%YAML:1.0\n"), Format::OpencvYaml);
        assert_eq!(sniff("T1_0: !!opencv-matrix\n"), Format::OpencvYaml);
        assert_eq!(sniff("[[1, 2]]"), Format::Moveit);
        assert_eq!(sniff("[INFO] driver started\n"), Format::Auto);
        assert_eq!(sniff("- effector_wrt_world:\n"), Format::MoveitYaml);
        assert_eq!(sniff("# c\nparameters:\n"), Format::EasyHandeye);
        assert_eq!(sniff("{\"a\": 1}\n"), Format::Auto);
    }
}
