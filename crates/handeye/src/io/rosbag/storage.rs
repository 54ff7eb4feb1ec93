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
) -> Result<BTreeMap<String, TopicInfo>> {
    match storage {
        Storage::Mcap => scan_mcap(file, wanted, on_message),
        Storage::Sqlite3 => scan_sqlite(file, wanted, on_message),
    }
}

fn scan_mcap(
    file: &Path,
    wanted: &dyn Fn(&str) -> bool,
    on_message: &mut dyn FnMut(Message<'_>) -> Result<()>,
) -> Result<BTreeMap<String, TopicInfo>> {
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
    // skipped (read above), and no record may claim more than the file holds.
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_skip_start_magic(true)
            .with_record_length_limit(usize::try_from(length).unwrap_or(usize::MAX)),
    );
    let mut schemas: HashMap<u16, String> = HashMap::new();
    let mut channels: HashMap<u16, (String, String, u16)> = HashMap::new();
    let mut topics: BTreeMap<String, TopicInfo> = BTreeMap::new();
    let mut k = 0usize;
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| mcap_error(file, k, e))? {
            LinearReadEvent::ReadRequest(n) => {
                let buffer = reader.insert(n.clamp(1, READ_SIZE));
                let read = f.read(buffer).map_err(io_error)?;
                reader.notify_read(read);
            }
            LinearReadEvent::Record { data, opcode } => {
                match mcap::parse_record(opcode, data).map_err(|e| mcap_error(file, k, e))? {
                    Record::Schema { header, .. } => {
                        schemas.insert(header.id, header.name);
                    }
                    Record::Channel(c) => {
                        channels.insert(c.id, (c.topic, c.message_encoding, c.schema_id));
                    }
                    Record::Message { header, data } => {
                        k += 1;
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
                        let info = topics.entry(topic.clone()).or_insert_with(|| TopicInfo {
                            msg_type: msg_type.to_string(),
                            encoding: encoding.clone(),
                            count: 0,
                        });
                        info.count += 1;
                        if wanted(topic) {
                            on_message(Message {
                                topic,
                                msg_type,
                                encoding,
                                data: &data,
                            })?;
                        }
                    }
                    _ => {}
                }
            }
        }
    }
    Ok(topics)
}

/// Bytes read from an MCAP file at a time.
const READ_SIZE: usize = 1 << 20;

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
        _ => "",
    };
    bag_error(
        file,
        None,
        format!("cannot read the SQLite3 recording ({what}): {e}{hint}"),
    )
}

fn scan_sqlite(
    file: &Path,
    wanted: &dyn Fn(&str) -> bool,
    on_message: &mut dyn FnMut(Message<'_>) -> Result<()>,
) -> Result<BTreeMap<String, TopicInfo>> {
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
    Ok(by_id.into_values().collect())
}
