//! The two storages of rosbag2: MCAP files (the `mcap` crate) and SQLite3 databases
//! (`rusqlite`), read as (topic, type, serialised bytes): MCAP in file order, SQLite3 by log time.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use crate::model::error::{Error, Result};

/// The storage of one file of a recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Storage {
    /// An `.mcap` file.
    Mcap,
    /// A `.db3` SQLite3 database.
    Sqlite3,
}

impl Storage {
    /// The storage of a file, by its extension.
    pub fn of(path: &Path) -> Option<Self> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("mcap") => Some(Self::Mcap),
            Some("db3") => Some(Self::Sqlite3),
            _ => None,
        }
    }
}

/// A topic of a file: its type and encoding, and how many messages it has.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct TopicInfo {
    pub msg_type: String,
    pub encoding: String,
    pub count: usize,
}

/// The topics of a recording by name and type: a name written with two types (two channels
/// of one topic, or two rows of a `topics` table) is two topics, each with its own count, so
/// that no message is lost from the totals.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Topics(BTreeMap<(String, String), TopicInfo>);

impl Topics {
    /// Counts `count` more messages of `name` with `info`'s type and encoding.
    pub fn add(&mut self, name: &str, info: &TopicInfo) {
        self.0
            .entry((name.to_string(), info.msg_type.clone()))
            .or_insert_with(|| TopicInfo {
                count: 0,
                ..info.clone()
            })
            .count += info.count;
    }

    /// Merges another file's topics.
    pub fn merge(&mut self, other: Topics) {
        for ((name, _), info) in other.0 {
            self.add(&name, &info);
        }
    }

    /// Whether a topic is named `name`.
    pub fn has(&self, name: &str) -> bool {
        self.of(name).next().is_some()
    }

    /// The topics named `name` (one per type).
    pub fn of<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a TopicInfo> + 'a {
        self.0
            .range((name.to_string(), String::new())..)
            .take_while(move |((n, _), _)| n == name)
            .map(|(_, info)| info)
    }

    /// Every topic by name, then type.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &TopicInfo)> {
        self.0.iter().map(|((name, _), info)| (name.as_str(), info))
    }

    /// The names, each once, sorted.
    pub fn names(&self) -> Vec<String> {
        let mut names: Vec<String> = self.iter().map(|(n, _)| n.to_string()).collect();
        names.dedup();
        names
    }

    /// Whether there is no topic.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// One message handed to the reader's callback.
pub(crate) struct Message<'a> {
    pub topic: &'a str,
    pub msg_type: &'a str,
    pub encoding: &'a str,
    pub data: &'a [u8],
}

/// The error of a file that cannot be read as its storage.
pub(crate) fn bag_error(file: &Path, at: Option<String>, message: impl Into<String>) -> Error {
    Error::Bag {
        file: file.display().to_string(),
        at,
        message: message.into(),
    }
}

const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";
const SQLITE_MAGIC: &[u8] = b"SQLite format 3\0";

/// Reads every message of `file`: `on_message` sees those of the topics `wanted` accepts, in the
/// file's order (MCAP: as written; SQLite3: by log time). Returns every topic with its count.
pub(crate) fn scan(
    file: &Path,
    storage: Storage,
    wanted: &dyn Fn(&str) -> bool,
    on_message: &mut dyn FnMut(Message<'_>) -> Result<()>,
) -> Result<Topics> {
    match storage {
        Storage::Mcap => scan_mcap(file, wanted, on_message),
        Storage::Sqlite3 => scan_sqlite(file, wanted, on_message),
    }
}

fn scan_mcap(
    file: &Path,
    wanted: &dyn Fn(&str) -> bool,
    on_message: &mut dyn FnMut(Message<'_>) -> Result<()>,
) -> Result<Topics> {
    use mcap::records::Record;
    use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
    use std::io::Read;

    let io_error = |e: std::io::Error| Error::Io {
        file: file.display().to_string(),
        source: e,
    };
    let mut f = std::fs::File::open(file).map_err(io_error)?;
    let length = f.metadata().map_err(io_error)?.len();
    let mut magic = [0u8; 8];
    let got = f.read(&mut magic).map_err(io_error)?;
    if got < magic.len() || magic != MCAP_MAGIC {
        return Err(bag_error(
            file,
            None,
            "not an MCAP file (it does not start with the MCAP magic bytes)",
        ));
    }
    // Streamed, so that a recording with camera images is not held in memory: the magic is
    // skipped (read above). No record may claim more than the file holds, or, inside a compressed
    // chunk (where a camera image may be larger than the whole file), more than
    // MAX_DECOMPRESSED_RECORD. Chunk CRCs are checked.
    let limit = usize::try_from(length)
        .unwrap_or(usize::MAX)
        .max(MAX_DECOMPRESSED_RECORD);
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_skip_start_magic(true)
            .with_validate_chunk_crcs(true)
            .with_record_length_limit(limit),
    );
    let mut schemas: HashMap<u16, String> = HashMap::new();
    let mut channels: HashMap<u16, (String, String, u16)> = HashMap::new();
    let mut topics = Topics::default();
    let mut counts = MessageCounts::default();
    let mut bomb = Bomb::new(length);
    let mut k = 0usize;
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| mcap_error(file, k, e))? {
            LinearReadEvent::ReadRequest(n) => {
                let buffer = reader.insert(n.clamp(1, READ_SIZE));
                let read = f.read(buffer).map_err(io_error)?;
                reader.notify_read(read);
            }
            LinearReadEvent::Record { data, opcode } => {
                bomb.record(data.len(), opcode == mcap::records::op::MESSAGE)
                    .map_err(|message| {
                        bag_error(file, Some(format!("after {k} message(s)")), message)
                    })?;
                match mcap::parse_record(opcode, data).map_err(|e| mcap_error(file, k, e))? {
                    Record::Schema { header, .. } => {
                        schemas.insert(header.id, header.name);
                    }
                    Record::Channel(c) => {
                        channels.insert(c.id, (c.topic, c.message_encoding, c.schema_id));
                    }
                    Record::Message { header, data } => {
                        k += 1;
                        counts.message(header.channel_id);
                        let Some((topic, encoding, schema_id)) = channels.get(&header.channel_id)
                        else {
                            return Err(bag_error(
                                file,
                                Some(format!("message {k}")),
                                format!(
                                    "the message names channel {}, which no channel record before it defines",
                                    header.channel_id
                                ),
                            ));
                        };
                        let msg_type = schemas.get(schema_id).map_or("", String::as_str);
                        topics.add(
                            topic,
                            &TopicInfo {
                                msg_type: msg_type.to_string(),
                                encoding: encoding.clone(),
                                count: 1,
                            },
                        );
                        if wanted(topic) {
                            on_message(Message {
                                topic,
                                msg_type,
                                encoding,
                                data: &data,
                            })?;
                        }
                    }
                    Record::MessageIndex(index) => counts
                        .indexed(index.channel_id, index.records.len())
                        .map_err(|lost| lost_error(file, k, &lost))?,
                    Record::Statistics(statistics) => counts.statistics = Some(statistics),
                    _ => {}
                }
            }
        }
    }
    counts.check().map_err(|lost| lost_error(file, k, &lost))?;
    Ok(topics)
}

/// Messages an MCAP file may hold beyond [`MESSAGES_PER_BYTE`] per byte stored. A recording
/// compressed by zstd stores a tf message in about 80 bytes (the test recordings: 73 KB for 882
/// messages); a file that unpacks to far more is a compression bomb (114 KB made 5 million tf
/// messages, 520 MB held) or damaged.
const MESSAGES_BASE: u64 = 100_000;
/// See [`MESSAGES_BASE`]: one message per byte stored, 80 times what compression gives.
const MESSAGES_PER_BYTE: u64 = 1;
/// Bytes an MCAP file may unpack to beyond [`UNPACKED_PER_BYTE`] per byte stored: a camera
/// image of a dark scene compresses a hundredfold, a file that unpacks much more only costs time.
const UNPACKED_BASE: u64 = 1 << 30;
/// See [`UNPACKED_BASE`].
const UNPACKED_PER_BYTE: u64 = 256;

/// The records an MCAP file unpacks to, against what its size allows ([`MESSAGES_BASE`],
/// [`UNPACKED_BASE`]): reading stops with an error once either is passed.
struct Bomb {
    length: u64,
    messages: u64,
    unpacked: u64,
}

impl Bomb {
    fn new(length: u64) -> Self {
        Self {
            length,
            messages: 0,
            unpacked: 0,
        }
    }

    /// Counts a record of `len` bytes; an error, in words, once the file unpacks to more than
    /// its size allows.
    fn record(&mut self, len: usize, message: bool) -> std::result::Result<(), String> {
        self.unpacked += len as u64 + 9;
        self.messages += u64::from(message);
        let most_messages = MESSAGES_BASE + MESSAGES_PER_BYTE.saturating_mul(self.length);
        let most_bytes = UNPACKED_BASE + UNPACKED_PER_BYTE.saturating_mul(self.length);
        let what = if self.messages > most_messages {
            format!("more than {most_messages} messages")
        } else if self.unpacked > most_bytes {
            format!("more than {} MB", most_bytes >> 20)
        } else {
            return Ok(());
        };
        Err(format!(
            "the file's {} bytes unpack to {what} (a recording compresses a message to tens of bytes, an image a hundredfold at most): a compression bomb or a damaged file, not read further",
            self.length
        ))
    }
}

/// Bytes read from an MCAP file at a time.
const READ_SIZE: usize = 1 << 20;

/// The largest record read from inside a compressed chunk, bytes (a 4K camera image is about
/// 25 MB): a decompression cannot make the reader hold more.
const MAX_DECOMPRESSED_RECORD: usize = 512 << 20;

/// The messages read from an MCAP file against those its indexes and statistics record, so that
/// no message is lost without a word: a chunk the linear reader skips (a damaged header that
/// claims no uncompressed data, say) leaves its messages in the chunk's message indexes and in the
/// summary's statistics.
#[derive(Default)]
struct MessageCounts {
    /// Per channel, messages read since that channel's last message index.
    since_index: HashMap<u16, usize>,
    /// Per channel, all messages read.
    read: HashMap<u16, u64>,
    /// The summary's statistics record, if the file has one.
    statistics: Option<mcap::records::Statistics>,
}

/// Messages an MCAP file records that were not read.
struct Lost {
    recorded: u64,
    read: u64,
    by: &'static str,
}

impl MessageCounts {
    fn message(&mut self, channel: u16) {
        *self.since_index.entry(channel).or_default() += 1;
        *self.read.entry(channel).or_default() += 1;
    }

    /// A chunk's message index for `channel`, listing `entries` messages: as many must have been
    /// read from the chunk just before it.
    fn indexed(&mut self, channel: u16, entries: usize) -> std::result::Result<(), Lost> {
        let read = self.since_index.remove(&channel).unwrap_or(0);
        if read < entries {
            return Err(Lost {
                recorded: entries as u64,
                read: read as u64,
                by: "a chunk's message index",
            });
        }
        Ok(())
    }

    /// The whole file against its statistics, per channel.
    fn check(&self) -> std::result::Result<(), Lost> {
        let Some(statistics) = &self.statistics else {
            return Ok(());
        };
        let read: u64 = self.read.values().sum();
        let short = statistics
            .channel_message_counts
            .iter()
            .any(|(channel, &n)| self.read.get(channel).copied().unwrap_or(0) < n);
        if read < statistics.message_count || short {
            return Err(Lost {
                recorded: statistics.message_count,
                read,
                by: "the file's statistics",
            });
        }
        Ok(())
    }
}

fn lost_error(file: &Path, k: usize, lost: &Lost) -> Error {
    bag_error(
        file,
        Some(format!("after {k} message(s)")),
        format!(
            "{} records {} message(s), {} could be read: a chunk is damaged and was skipped (`mcap recover` rescues the complete chunks into a new file)",
            lost.by, lost.recorded, lost.read
        ),
    )
}

fn mcap_error(file: &Path, k: usize, e: mcap::McapError) -> Error {
    let hint = match e {
        mcap::McapError::UnexpectedEof | mcap::McapError::BadMagic | mcap::McapError::BadFooter => {
            ": the file is truncated or damaged (was the recording stopped cleanly? `mcap recover` rescues its complete chunks)"
        }
        _ => "",
    };
    bag_error(
        file,
        Some(format!("after {k} message(s)")),
        format!("cannot read the MCAP file: {e}{hint}"),
    )
}

fn sqlite_error(file: &Path, what: &str, e: rusqlite::Error) -> Error {
    let hint = match &e {
        rusqlite::Error::SqliteFailure(f, _)
            if matches!(
                f.code,
                rusqlite::ErrorCode::DatabaseCorrupt | rusqlite::ErrorCode::NotADatabase
            ) =>
        {
            ": the file is truncated or damaged (was the recording stopped cleanly?)"
        }
        rusqlite::Error::SqliteFailure(f, _)
            if f.code == rusqlite::ErrorCode::OperationInterrupted =>
        {
            ": stopped after more work than a recording of its size needs (a damaged database?)"
        }
        _ => "",
    };
    bag_error(
        file,
        None,
        format!("cannot read the SQLite3 recording ({what}): {e}{hint}"),
    )
}

/// SQLite virtual-machine steps allowed per byte of a recording, and in any case: far above what
/// reading a recording takes (tens of steps per message of at least tens of bytes), so that only a
/// query that does not end reaches it.
const SQLITE_OPS_PER_BYTE: u64 = 1_000;
/// See [`SQLITE_OPS_PER_BYTE`].
const SQLITE_OPS_BASE: u64 = 100_000_000;
/// Steps between two calls of the progress handler.
const SQLITE_OPS_PER_CALL: i32 = 10_000;

/// Refuses a recording whose `topics` or `messages` is not a plain table: a view (or a virtual
/// table) runs whatever query the file holds, which may never end.
fn check_tables(file: &Path, db: &rusqlite::Connection) -> Result<()> {
    for name in ["topics", "messages"] {
        let found: Option<(String, String)> = db
            .query_row(
                "SELECT type, coalesce(sql, '') FROM sqlite_master WHERE name = ?1",
                [name],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .map(Some)
            .or_else(|e| match e {
                rusqlite::Error::QueryReturnedNoRows => Ok(None),
                e => Err(e),
            })
            .map_err(|e| sqlite_error(file, "its schema", e))?;
        let plain = found.as_ref().is_some_and(|(kind, sql)| {
            kind == "table"
                && !sql
                    .trim_start()
                    .to_ascii_uppercase()
                    .starts_with("CREATE VIRTUAL")
        });
        if !plain {
            let what = match &found {
                None => "is missing".to_string(),
                Some((kind, _)) if kind != "table" => format!("is a {kind}, not a table"),
                Some(_) => "is a virtual table".to_string(),
            };
            return Err(bag_error(
                file,
                None,
                format!("not a rosbag2 SQLite3 recording: `{name}` {what}"),
            ));
        }
    }
    Ok(())
}

fn scan_sqlite(
    file: &Path,
    wanted: &dyn Fn(&str) -> bool,
    on_message: &mut dyn FnMut(Message<'_>) -> Result<()>,
) -> Result<Topics> {
    use rusqlite::{Connection, OpenFlags};
    // Check the file before SQLite sees it: SQLite would create or misread it.
    let mut head = [0u8; 16];
    let read = std::fs::File::open(file)
        .and_then(|mut f| std::io::Read::read(&mut f, &mut head))
        .map_err(|e| Error::Io {
            file: file.display().to_string(),
            source: e,
        })?;
    if read < head.len() || head != SQLITE_MAGIC {
        return Err(bag_error(
            file,
            None,
            "not a SQLite3 database (it does not start with `SQLite format 3`)",
        ));
    }
    let db = Connection::open_with_flags(
        file,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
    .map_err(|e| sqlite_error(file, "open", e))?;
    check_tables(file, &db)?;
    // A database can hold a query that never ends even over tables (a recursive trigger cannot
    // run on a read, but a damaged page can loop): the work is bounded by the file's size.
    let length = std::fs::metadata(file).map_or(0, |m| m.len());
    let budget = SQLITE_OPS_PER_BYTE.saturating_mul(length) + SQLITE_OPS_BASE;
    let mut spent = 0u64;
    db.progress_handler(
        SQLITE_OPS_PER_CALL,
        Some(move || {
            spent += SQLITE_OPS_PER_CALL as u64;
            spent > budget
        }),
    );
    let mut by_id: BTreeMap<i64, (String, TopicInfo)> = BTreeMap::new();
    {
        let mut q = db
            .prepare("SELECT id, name, type, serialization_format FROM topics")
            .map_err(|e| sqlite_error(file, "the topics table", e))?;
        let rows = q
            .query_map([], |r| {
                Ok((
                    r.get::<_, i64>(0)?,
                    r.get::<_, String>(1)?,
                    r.get::<_, String>(2)?,
                    r.get::<_, String>(3)?,
                ))
            })
            .map_err(|e| sqlite_error(file, "the topics table", e))?;
        for row in rows {
            let (id, name, msg_type, encoding) =
                row.map_err(|e| sqlite_error(file, "the topics table", e))?;
            by_id.insert(
                id,
                (
                    name,
                    TopicInfo {
                        msg_type,
                        encoding,
                        count: 0,
                    },
                ),
            );
        }
    }
    let mut q = db
        .prepare("SELECT topic_id, data FROM messages ORDER BY timestamp, id")
        .map_err(|e| sqlite_error(file, "the messages table", e))?;
    let mut rows = q
        .query([])
        .map_err(|e| sqlite_error(file, "the messages table", e))?;
    let mut k = 0usize;
    loop {
        let row = match rows.next() {
            Ok(Some(row)) => row,
            Ok(None) => break,
            Err(e) => return Err(sqlite_error(file, &format!("message {}", k + 1), e)),
        };
        k += 1;
        let id: i64 = row
            .get(0)
            .map_err(|e| sqlite_error(file, &format!("message {k}"), e))?;
        let Some((name, info)) = by_id.get_mut(&id) else {
            return Err(bag_error(
                file,
                Some(format!("message {k}")),
                format!("the message names topic id {id}, which the topics table does not have"),
            ));
        };
        info.count += 1;
        if wanted(name) {
            let data = row
                .get_ref(1)
                .and_then(|v| v.as_blob().map_err(rusqlite::Error::from))
                .map_err(|e| sqlite_error(file, &format!("message {k}"), e))?;
            on_message(Message {
                topic: name,
                msg_type: &info.msg_type,
                encoding: &info.encoding,
                data,
            })?;
        }
    }
    let mut topics = Topics::default();
    for (name, info) in by_id.into_values() {
        topics.add(&name, &info);
    }
    Ok(topics)
}
