//! Streaming reader of ROS 2 sqlite3 bags (`.db3`, the default storage of ROS 2 Humble's
//! `ros2 bag record`; see `docs/log-format.md#ros-2-sqlite3-bags-db3`): one `.db3` file, or a bag
//! directory with `metadata.yaml`.
//!
//! The topics, message types and CDR payloads are those of the MCAP form, converted by the same
//! code ([`crate::ros`]): `messages.timestamp` (the receive time, ns) plays the MCAP log time.
//! Each file's `messages` are read in the order of `ORDER BY timestamp, id` (the payloads of
//! configured topics only; every row's id where the rows are accounted, `db3/account.rs`):
//! through the time index ([`Db3Reader::open`]), or for the audit in the table's own order, put
//! back into time order on the way ([`Db3Reader::open_in_row_order`], [`hold_back`]), streamed by a thread
//! that owns the read-only SQLite connection and hands rows over in small batches through a
//! bounded channel (memory stays flat but for the accounting's bit per row, at most 16 MiB); the
//! files of a bag are read one after the other, in the order of `relative_file_paths`, and their
//! messages put in time order within `mcap.reorder_window` like any others.
//!
//! The pacs header: given by the caller (`pacs audit --header`), or the JSON text in key
//! [`CUSTOM_DATA_KEY`] of the bag's `custom_data` (in `metadata.yaml`, or for a lone `.db3` file in
//! its `metadata` table, which newer rosbag2 releases and `rosbags` write).

use crate::error::{Location, LogError};
use crate::format::{Header, ModelOverrides, Record, RecordReader};
use crate::mcap::{McapConfig, RECORD_LIMIT, parse_header_json};
use crate::ros::{Message, Messages, Pending, Stream};
use rusqlite::types::ValueRef;
use rusqlite::{Connection, OpenFlags};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};

mod account;
mod metadata;
use account::RowAccount;
use metadata::{BagInfo, bag_info};

/// The 16 bytes every SQLite 3 database file starts with.
pub const SQLITE_MAGIC: &[u8] = b"SQLite format 3\0";
/// The key of the bag's `custom_data` whose value is the pacs header's JSON text.
pub const CUSTOM_DATA_KEY: &str = "pacs_header";
/// The bag directory's metadata file.
pub const METADATA_FILE: &str = "metadata.yaml";
/// Largest `metadata.yaml` read, in bytes.
const METADATA_LIMIT: u64 = 1 << 20;
/// Rows per batch handed from the reading thread (fewer when their payloads reach
/// [`BATCH_BYTES`]).
const BATCH: usize = 1024;
/// Payload bytes after which a batch is handed over.
const BATCH_BYTES: usize = 1 << 20;
/// Payload bytes per row a new batch reserves (a 7-joint `JointState` with names and
/// velocities is about 280 bytes).
const BYTES_PER_ROW: usize = 320;
/// Batches in flight between the reading thread and the reader.
const BATCHES_IN_FLIGHT: usize = 4;

/// Whether `prefix` (the first bytes of a file) starts with the SQLite 3 magic.
pub fn has_magic(prefix: &[u8]) -> bool {
    prefix.starts_with(SQLITE_MAGIC)
}

/// Whether `path` is a rosbag2 bag directory: a directory holding a `metadata.yaml` — in any form
/// (also one that is no regular file, or a dangling link: reading it then fails and names it,
/// rather than the directory's parts being taken for logs of their own).
pub fn is_bag_dir(path: &Path) -> bool {
    path.is_dir() && std::fs::symlink_metadata(path.join(METADATA_FILE)).is_ok()
}

/// Refuse a file given alone that is one of several parts of a bag: the `metadata.yaml` beside
/// it lists it in `relative_file_paths` with other files (a split recording, e.g. ROS 2 Humble's
/// `--max-bag-size`, whose files carry no metadata of their own). One part is not the run: a
/// violation in another part would go unseen. The `metadata.yaml` is looked for beside the path
/// given and beside the file it names (through a symbolic link); one that cannot be read or
/// contradicts itself is refused too (what it says about the file cannot be known); one that
/// does not list the file says nothing about it. A `metadata.yaml` that lists the file as the
/// bag's only part describes it (its message counts, its header): the bag directory is returned,
/// to be read instead of the file alone (the same bytes then get the same checks either way).
pub fn refuse_one_part(path: &Path) -> Result<Option<PathBuf>, LogError> {
    if path.is_dir() {
        return Ok(None);
    }
    let real = path.canonicalize().ok();
    let mut dirs = vec![crate::format::dir_of(path)];
    if let Some(d) = real.as_deref().map(crate::format::dir_of)
        && !dirs.contains(&d)
    {
        dirs.push(d);
    }
    for dir in dirs {
        if refuse_part_of(path, real.as_deref(), &dir)? {
            return Ok(Some(dir));
        }
    }
    Ok(None)
}

/// [`refuse_one_part`] for the `metadata.yaml` of the directory `dir` (one in any form counts:
/// one that is no regular file, or a dangling link, cannot be read and is refused). Returns
/// whether that metadata lists the file as the bag's only part.
fn refuse_part_of(path: &Path, real: Option<&Path>, dir: &Path) -> Result<bool, LogError> {
    if std::fs::symlink_metadata(dir.join(METADATA_FILE)).is_err() {
        return Ok(false);
    }
    let name = path.display().to_string();
    let (info, meta_name) = read_bag_metadata(dir).map_err(|e| {
        LogError::input(
            &name,
            Location::File,
            format!(
                "beside it, {} cannot be read as a bag's metadata ({e}): whether this file is the whole recording or one part of it cannot be told (audit the bag directory, or the file away from that metadata)",
                dir.join(METADATA_FILE).display()
            ),
        )
    })?;
    let own: Vec<&str> = [path.file_name(), real.and_then(Path::file_name)]
        .into_iter()
        .flatten()
        .filter_map(|n| n.to_str())
        .collect();
    let listed = |f: &String| {
        let f = f.trim_start_matches("./");
        own.contains(&f) || (real.is_some() && dir.join(f).canonicalize().ok().as_deref() == real)
    };
    if info.files.len() > 1 && info.files.iter().any(listed) {
        return Err(LogError::input(
            &name,
            Location::File,
            format!(
                "this file is one of {} parts of the bag described by {meta_name} ({}): audit the bag directory {}, not one part",
                info.files.len(),
                info.files.join(", "),
                dir.display()
            ),
        ));
    }
    Ok(info.files.iter().any(listed))
}

/// The parsed `metadata.yaml` of the bag directory `path` (at most [`METADATA_LIMIT`] bytes) and
/// the name errors about it use.
fn read_bag_metadata(path: &Path) -> Result<(BagInfo, String), LogError> {
    let meta = path.join(METADATA_FILE);
    let meta_name = meta.display().to_string();
    let bad = |p: String| LogError::input(&meta_name, Location::File, p);
    let io = |e: std::io::Error| LogError::Io {
        file: meta_name.clone(),
        source: e,
    };
    let m = std::fs::metadata(&meta).map_err(io)?;
    if !m.is_file() {
        // A FIFO would block the reading; a directory is no metadata.
        return Err(bad(
            "not a regular file (a directory, FIFO, socket or device)".into(),
        ));
    }
    let len = m.len();
    if len > METADATA_LIMIT {
        return Err(bad(format!(
            "{len} bytes: larger than the {METADATA_LIMIT} bytes read"
        )));
    }
    let text = std::fs::read_to_string(&meta).map_err(io)?;
    let info = bag_info(&text, false).map_err(|e| bad(e.to_string()))?;
    Ok((info, meta_name))
}

/// The files of the bag directory `path` in the metadata's order: each listed one must be a file,
/// and no file ending in `.{ext}` may be in the directory unlisted (a part the metadata does not
/// list would go unread: the metadata would not describe the recording in the directory).
fn bag_files(
    path: &Path,
    info: &BagInfo,
    meta_name: &str,
    ext: &str,
) -> Result<Vec<PathBuf>, LogError> {
    let bad = |p: String| LogError::input(meta_name, Location::File, p);
    if info.files.is_empty() {
        return Err(bad(
            "rosbag2_bagfile_information.relative_file_paths: no files".into(),
        ));
    }
    let mut files = Vec::new();
    for (i, f) in info.files.iter().enumerate() {
        let p = path.join(f);
        if !p.is_file() {
            return Err(bad(format!(
                "rosbag2_bagfile_information.relative_file_paths[{i}]: `{}` is not a file",
                p.display()
            )));
        }
        files.push(p);
    }
    let listed: Vec<PathBuf> = files.iter().filter_map(|p| p.canonicalize().ok()).collect();
    let entries = std::fs::read_dir(path).map_err(|e| LogError::Io {
        file: path.display().to_string(),
        source: e,
    })?;
    for e in entries.flatten() {
        let p = e.path();
        let part = p.extension().is_some_and(|x| x.eq_ignore_ascii_case(ext));
        let is_listed = p.canonicalize().is_ok_and(|c| listed.contains(&c));
        if part && p.is_file() && !is_listed {
            return Err(bad(format!(
                "`{}` is in the bag directory but not in rosbag2_bagfile_information.relative_file_paths ({}): the metadata does not describe the whole recording",
                p.display(),
                info.files.join(", ")
            )));
        }
        // Another log inside the bag directory (a file of another form, or one in a
        // subdirectory) is no part of the bag: audited as the bag, it would go unseen, also in
        // a fleet's archive (whose walk takes the bag directory as one log).
        let other = if e.file_type().is_ok_and(|k| k.is_dir()) {
            log_below(&p, 8)
        } else if !part && !is_listed && has_log_name(&p) {
            Some(p.clone())
        } else {
            None
        };
        if let Some(o) = other {
            return Err(bad(format!(
                "`{}` is a log inside the bag directory but not one of the bag's files ({}): it would go unaudited; move it out of the bag directory and audit it on its own",
                o.display(),
                info.files.join(", ")
            )));
        }
    }
    Ok(files)
}

/// The file extensions of logs (JSON Lines, CSV, MCAP, ROS 2 sqlite3 bags).
pub const LOG_EXTENSIONS: [&str; 4] = ["jsonl", "csv", "mcap", "db3"];

/// Whether `p` is named as a log ([`LOG_EXTENSIONS`], any case).
pub fn has_log_name(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| LOG_EXTENSIONS.iter().any(|x| e.eq_ignore_ascii_case(x)))
}

/// A log-named file in the directory `dir` or its subdirectories (up to `depth` levels; symbolic
/// links to directories not followed), if any.
fn log_below(dir: &Path, depth: usize) -> Option<PathBuf> {
    for e in std::fs::read_dir(dir).ok()?.flatten() {
        let p = e.path();
        if e.file_type().is_ok_and(|k| k.is_dir()) {
            if depth > 0
                && let Some(f) = log_below(&p, depth - 1)
            {
                return Some(f);
            }
        } else if has_log_name(&p) {
            return Some(p);
        }
    }
    None
}

/// A rosbag2 bag directory in the MCAP storage (`storage_identifier: mcap`: the default of
/// `ros2 bag record` from ROS 2 Iron on): its `.mcap` files in the metadata's order, the pacs
/// header text of its `custom_data` key [`CUSTOM_DATA_KEY`] if it has one, and the recorder's
/// message counts per topic.
#[derive(Debug)]
pub struct McapBag {
    /// The bag directory.
    pub dir: PathBuf,
    /// The bag's files, in the order `relative_file_paths` lists them.
    pub files: Vec<PathBuf>,
    /// The JSON text of the metadata's `custom_data` header ([`McapBag::header`] parses it).
    pub header_json: Option<String>,
    /// `topics_with_message_count`: messages per topic, as the recorder counted them.
    pub topic_counts: Vec<(String, u64)>,
    /// `metadata.yaml`'s path, as errors about it name it.
    pub metadata: String,
}

impl McapBag {
    /// The metadata's `custom_data` header (relative robot paths rebased to the bag), if any;
    /// errors name `metadata.yaml` and the key.
    pub fn header(&self) -> Result<Option<Header>, LogError> {
        self.header_json
            .as_deref()
            .map(|json| custom_data_header(json, &self.metadata, &self.dir))
            .transpose()
    }
}

/// The pacs header in a bag's `custom_data` key [`CUSTOM_DATA_KEY`] (`json`, read from
/// `meta_name`, which errors name), relative `{urdf, side}` robot paths rebased to `dir`.
fn custom_data_header(json: &str, meta_name: &str, dir: &Path) -> Result<Header, LogError> {
    let mut h = parse_header_json(json).map_err(|e| {
        LogError::input(
            meta_name,
            Location::File,
            format!("custom_data.{CUSTOM_DATA_KEY}: {e}"),
        )
    })?;
    h.robot.rebase(dir);
    Ok(h)
}

/// A bag's `topics_with_message_count` (`expected`, stated in `file`) against the messages read
/// per topic (`read`): every watched topic ([`Messages::watches`]; one on no channel or
/// connection of any file counts as 0 read) must hold as many as the recorder counted; fewer
/// means a file was cut short or a part is missing, more that the metadata is not these files'.
/// Topics the audit does not read are not counted. A topic recorded on several connections
/// (publishers with different QoS: rosbag2 lists it once per connection, each with its own count)
/// is compared by its total. The one check of both ROS bag readers.
pub(crate) fn check_topic_counts(
    file: &str,
    expected: &[(String, u64)],
    read: impl Fn(&str) -> u64,
    conv: &Messages,
) -> Result<(), LogError> {
    // Per topic name, in the metadata's order: the sum over its entries.
    let mut totals: Vec<(&str, u64)> = Vec::new();
    for (topic, n) in expected {
        match totals.iter_mut().find(|(t, _)| *t == topic.as_str()) {
            Some((_, sum)) => *sum = sum.saturating_add(*n),
            None => totals.push((topic.as_str(), *n)),
        }
    }
    for (topic, want) in totals {
        if !conv.watches(topic) {
            continue;
        }
        let read = read(topic);
        if read != want {
            return Err(LogError::input(
                file,
                Location::File,
                format!(
                    "topics_with_message_count: `{topic}` has message_count {want} (over its entries), the bag's files hold {read} of its messages ({})",
                    if read < want {
                        "a file was cut short or a part is missing: the bag is not the whole recording"
                    } else {
                        "the metadata does not describe these files"
                    }
                ),
            ));
        }
    }
    Ok(())
}

/// The MCAP bag at `path`, or `None` where `path` is not a bag directory in the MCAP storage.
/// Errors (naming `metadata.yaml` and the field): metadata that cannot be read, a compressed
/// bag, a listed file missing or not MCAP, a `.mcap` file the metadata does not list.
pub fn mcap_bag(path: &Path) -> Result<Option<McapBag>, LogError> {
    if !is_bag_dir(path) {
        return Ok(None);
    }
    let (info, meta_name) = read_bag_metadata(path)?;
    if info.storage.as_deref() != Some("mcap") {
        return Ok(None);
    }
    let bad = |p: String| LogError::input(&meta_name, Location::File, p);
    if info.messages_zstd() {
        // Read for sqlite3 bags only: say so rather than the general message.
        return Err(bad(format!(
            "compression_mode `{}` with compression_format `{}` is read for sqlite3 bags only, not in the MCAP storage (MCAP's own chunk compression is read): decompress the bag first (e.g. `ros2 bag convert`)",
            info.compression_mode, info.compression_format
        )));
    }
    info.check_compression().map_err(|e| bad(e.to_string()))?;
    let files = bag_files(path, &info, &meta_name, "mcap")?;
    for (i, f) in files.iter().enumerate() {
        let mut magic = Vec::with_capacity(8);
        let read = std::fs::File::open(f).and_then(|file| {
            std::io::Read::read_to_end(&mut std::io::Read::take(file, 8), &mut magic)
        });
        if read.is_err() || !crate::mcap::has_magic(&magic) {
            return Err(bad(format!(
                "rosbag2_bagfile_information.relative_file_paths[{i}]: `{}` is not an MCAP file (no MCAP magic), yet storage_identifier is `mcap`",
                f.display()
            )));
        }
    }
    Ok(Some(McapBag {
        dir: path.to_path_buf(),
        files,
        header_json: info.pacs_header,
        topic_counts: info.topic_counts,
        metadata: meta_name,
    }))
}

/// One row of `messages`; its payload is `data` of its batch's bytes.
#[derive(Clone)]
struct Row {
    id: i64,
    topic_id: i64,
    timestamp: i64,
    data: std::ops::Range<usize>,
}

/// Rows handed over at once, their payloads one after the other in `bytes` (one buffer per
/// batch, not per row; batches read go back to the thread to be refilled).
#[derive(Default)]
struct Rows {
    rows: Vec<Row>,
    bytes: Vec<u8>,
}

enum Batch {
    Rows(Rows),
    End,
    /// Why reading stopped (the row id reached, and the problem).
    Err(Location, Db3Problem),
}

/// The rows of one file, read by a thread (see the module docs).
struct RowStream {
    rx: Option<Receiver<Batch>>,
    /// Batches read, handed back to the thread for reuse (no allocation per batch).
    back: SyncSender<Rows>,
    /// The batch being read, and its next row.
    batch: Rows,
    next: usize,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Drop for RowStream {
    fn drop(&mut self) {
        // Closing the channel stops the thread at its next send.
        self.rx = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// What is known about one `.db3` file after opening it.
struct Part {
    path: PathBuf,
    name: String,
    /// Every topic of the file, in increasing `topics.id` (looked up by binary search, once
    /// per row).
    topics: Vec<PartTopic>,
    /// The rows the file holds (every topic) by the metadata's count, when its completeness is
    /// checked by accounting ([`account`]) rather than by `quick_check` before reading.
    accounted_rows: Option<u64>,
}

/// One row of a file's `topics` table, and the rows of it read so far.
struct PartTopic {
    id: i64,
    name: String,
    stream: Stream,
    read: u64,
}

impl Part {
    /// The ids of the configured topics, in increasing order.
    fn configured_ids(&self) -> Vec<i64> {
        self.topics
            .iter()
            .filter(|t| t.stream != Stream::Ignored)
            .map(|t| t.id)
            .collect()
    }

    /// The index in `topics` of `topics.id` `id`.
    fn topic_index(&self, id: i64) -> Option<usize> {
        self.topics.binary_search_by_key(&id, |t| t.id).ok()
    }
}

/// Streaming reader of a ROS 2 sqlite3 bag; see the module docs.
pub struct Db3Reader {
    /// The bag as given (file or directory): names the run and downstream errors.
    name: String,
    parts: Vec<Part>,
    /// Index of the part being read (`parts.len()` when all are read).
    part: usize,
    rows: Option<RowStream>,
    conv: Messages,
    done: bool,
    current: Option<Pending>,
    /// The metadata's messages per topic (`topics_with_message_count`), and the metadata's name.
    expected: Vec<(String, u64)>,
    info_name: String,
    /// Where the header was read from, when not given: the metadata (`info_name`).
    header_file: Option<String>,
    /// The payloads' decompression, for a bag with zstd message compression.
    payload_zstd: Option<PayloadZstd>,
    /// Whether each file's rows are read in storage order (`ORDER BY id`), checked to be time
    /// order ([`Db3Reader::open_in_row_order`]), rather than through the time index.
    row_order: bool,
}

fn open_ro(path: &Path) -> Result<Connection, Db3Problem> {
    let c = Connection::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
    .map_err(Db3Problem::Open)?;
    // Reading never writes: refuse anything that would (e.g. a hot journal to roll back).
    c.pragma_update(None, "query_only", true)
        .map_err(Db3Problem::Open)?;
    // The time-ordered query may sort: on disk, never an unbounded in-memory sorter.
    c.pragma_update(None, "temp_store", "FILE")
        .map_err(Db3Problem::Open)?;
    Ok(c)
}

/// What SQLite says, with a hint for the usual cause of each kind of failure.
fn sqlite_problem(e: &rusqlite::Error) -> String {
    use rusqlite::ErrorCode;
    match e.sqlite_error_code() {
        Some(ErrorCode::NotADatabase) => format!("not an SQLite database ({e})"),
        Some(ErrorCode::DatabaseCorrupt) => {
            format!("damaged or truncated SQLite file ({e})")
        }
        _ => e.to_string(),
    }
}

/// Check the SQLite header against the file length: a file shorter than the page count its header
/// states is truncated (SQLite itself reads missing pages as zeros only where it reaches them).
fn check_size(path: &Path, name: &str) -> Result<(), LogError> {
    use std::io::Read;
    let io = |e: std::io::Error| LogError::Io {
        file: name.to_string(),
        source: e,
    };
    let mut f = std::fs::File::open(path).map_err(io)?;
    let len = f.metadata().map_err(io)?.len();
    let mut h = Vec::with_capacity(100);
    (&mut f).take(100).read_to_end(&mut h).map_err(io)?;
    let bad = |p: String| LogError::input(name, Location::File, p);
    if !has_magic(&h) {
        return Err(bad(
            "not an SQLite database: the file does not start with `SQLite format 3\\0`".into(),
        ));
    }
    if h.len() < 100 {
        return Err(bad(format!(
            "truncated file: {} bytes, shorter than the 100-byte SQLite header",
            h.len()
        )));
    }
    let be32 = |i: usize| u32::from_be_bytes([h[i], h[i + 1], h[i + 2], h[i + 3]]);
    let page = match u16::from_be_bytes([h[16], h[17]]) {
        1 => 65536u64,
        p => u64::from(p),
    };
    // The in-header page count is valid when the change counter matches "version valid for".
    let pages = u64::from(be32(28));
    if be32(24) == be32(92) && pages > 0 && page.saturating_mul(pages) > len {
        return Err(bad(format!(
            "truncated file: the SQLite header states {pages} pages of {page} bytes ({} bytes), the file has {len} bytes",
            page * pages
        )));
    }
    Ok(())
}

/// What is wrong with a bag's SQLite file (the caller names the file and the row).
#[derive(Debug, thiserror::Error)]
enum Db3Problem {
    #[error("cannot open as SQLite: {0}")]
    Open(rusqlite::Error),
    #[error("{}{}", table.map(|t| format!("table `{t}`: ")).unwrap_or_default(), sqlite_problem(error))]
    Sqlite {
        table: Option<&'static str>,
        error: rusqlite::Error,
    },
    #[error("reading messages{}: {}", after.map(|id| format!(" after message id {id}")).unwrap_or_default(), sqlite_problem(error))]
    Reading {
        after: Option<i64>,
        error: rusqlite::Error,
    },
    #[error("{what}: not valid UTF-8")]
    NotUtf8 { what: String },
    #[error("{what}: expected {expected}, found {found}")]
    CellType {
        what: String,
        expected: &'static str,
        found: rusqlite::types::Type,
    },
    #[error("messages.data: {0} bytes, over the {RECORD_LIMIT}-byte message limit")]
    TooLarge(usize),
    #[error(
        "damaged SQLite file (its rows are not the ids 1 to the metadata's message_count, and PRAGMA quick_check: {0})"
    )]
    Damaged(String),
    /// Rows not as many as the metadata counts.
    #[error("{0}")]
    Miscounted(String),
    /// Read in storage order, a row is stamped before the last row handed over.
    #[error("rows not stored in time order")]
    NotInRowOrder,
}

impl Db3Problem {
    fn sqlite(error: rusqlite::Error) -> Self {
        Db3Problem::Sqlite { table: None, error }
    }
}

/// A text cell, or why it is not one.
fn text(v: ValueRef<'_>, what: &str) -> Result<String, Db3Problem> {
    match v {
        ValueRef::Text(t) => std::str::from_utf8(t)
            .map(str::to_string)
            .map_err(|_| Db3Problem::NotUtf8 { what: what.into() }),
        other => Err(Db3Problem::CellType {
            what: what.into(),
            expected: "text",
            found: other.data_type(),
        }),
    }
}

/// An integer cell, or why it is not one.
fn int(v: ValueRef<'_>, what: &str) -> Result<i64, Db3Problem> {
    match v {
        ValueRef::Integer(i) => Ok(i),
        other => Err(Db3Problem::CellType {
            what: what.into(),
            expected: "an integer",
            found: other.data_type(),
        }),
    }
}

/// SQLite's structural check of every page (b-trees, free list), `Ok(None)` if the file passes,
/// else SQLite's first complaint.
fn quick_check(conn: &Connection) -> Result<Option<String>, rusqlite::Error> {
    let check: String = conn.query_row("PRAGMA quick_check(1)", [], |r| r.get(0))?;
    Ok((check != "ok").then_some(check))
}

/// Open one `.db3` file: its tables, and its topics checked against the configuration.
/// `counted_rows`: the rows the metadata says the file holds (every topic), if it says.
fn open_part(
    path: PathBuf,
    counted_rows: Option<u64>,
    conv: &mut Messages,
) -> Result<Part, LogError> {
    let name = path.display().to_string();
    check_size(&path, &name)?;
    let bad = |p: String| LogError::input(&name, Location::File, p);
    let conn = open_ro(&path).map_err(|e| bad(e.to_string()))?;
    let sql = |e: rusqlite::Error| bad(sqlite_problem(&e));
    for table in ["topics", "messages"] {
        let n: i64 = conn
            .query_row(
                "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = ?1",
                [table],
                |r| r.get(0),
            )
            .map_err(sql)?;
        if n == 0 {
            return Err(bad(format!(
                "not a rosbag2 sqlite3 bag: no table `{table}`"
            )));
        }
    }
    let mut stmt = conn
        .prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id")
        .map_err(|e| bad(format!("table `topics`: {}", sqlite_problem(&e))))?;
    let mut rows = stmt.query([]).map_err(sql)?;
    let mut topics: Vec<PartTopic> = Vec::new();
    while let Some(r) = rows.next().map_err(sql)? {
        let cell = |i: usize| r.get_ref(i).map_err(|e| bad(sqlite_problem(&e)));
        let cell_bad = |e: Db3Problem| bad(e.to_string());
        let id = int(cell(0)?, "topics.id").map_err(cell_bad)?;
        let at = |c: &str| format!("topics row id {id}: {c}");
        let topic = text(cell(1)?, &at("name")).map_err(cell_bad)?;
        let typ = text(cell(2)?, &at("type")).map_err(cell_bad)?;
        let ser = text(cell(3)?, &at("serialization_format")).map_err(cell_bad)?;
        let (stream, expected) = conv
            .stream_of(&topic, Some(&typ))
            .map_err(|e| bad(e.to_string()))?;
        if stream != Stream::Ignored {
            let what = format!("topic `{topic}` (topics id {id})");
            if typ != expected {
                return Err(bad(format!(
                    "{what}: type `{typ}`, expected `{expected}` for this topic"
                )));
            }
            if ser != "cdr" {
                return Err(bad(format!(
                    "{what}: serialization format `{ser}` is not supported (expected `cdr`)"
                )));
            }
        }
        topics.push(PartTopic {
            id,
            name: topic,
            stream,
            read: 0,
        });
    }
    topics.sort_by_key(|t| t.id);
    if let Some(w) = topics.windows(2).find(|w| w[0].id == w[1].id) {
        return Err(bad(format!("table `topics`: id {} appears twice", w[0].id)));
    }
    // Completeness: accounting for the rows `1..=N` while reading, where the metadata counts
    // them and the table's largest id (its own b-tree's last row, not the index) agrees;
    // otherwise SQLite's structural check of every page now, so that a damaged file is refused
    // before anything is read from it rather than read as far as the damage lets SQLite notice.
    let accounted_rows = match counted_rows {
        Some(n) if n <= account::MAX_ACCOUNTED_ROWS => {
            let last: Option<i64> = conn
                .query_row("SELECT max(id) FROM messages", [], |r| r.get(0))
                .map_err(sql)?;
            (last.unwrap_or(0) == n as i64).then_some(n)
        }
        _ => None,
    };
    // Where the metadata counts the file's rows but they cannot be accounted for while reading,
    // the count itself must hold: a file holding more or fewer rows than its metadata says (rows
    // cut or added by an editing tool) is not the recording the metadata describes.
    if let (Some(n), None) = (counted_rows, accounted_rows) {
        let rows: i64 = conn
            .query_row("SELECT count(*) FROM messages", [], |r| r.get(0))
            .map_err(sql)?;
        if u64::try_from(rows).ok() != Some(n) {
            return Err(bad(miscounted(n, rows)));
        }
    }
    if accounted_rows.is_none()
        && let Some(complaint) = quick_check(&conn).map_err(sql)?
    {
        return Err(bad(format!(
            "damaged SQLite file (PRAGMA quick_check: {complaint})"
        )));
    }
    Ok(Part {
        path,
        name,
        topics,
        accounted_rows,
    })
}

/// The complaint about a file whose rows are not as many as its metadata counts.
fn miscounted(counted: u64, rows: i64) -> String {
    format!(
        "the bag's metadata counts {counted} messages in this file (message_count), it holds {rows}: the metadata does not describe this file (rows cut or added?)"
    )
}

/// The metadata YAML a `.db3` file keeps in its `metadata` table (newer rosbag2 releases, and
/// `rosbags`), if it has one.
fn db_metadata(path: &Path, name: &str) -> Result<Option<String>, LogError> {
    let bad = |p: String| LogError::input(name, Location::File, p);
    let conn = open_ro(path).map_err(|e| bad(e.to_string()))?;
    let sql = |e: rusqlite::Error| bad(sqlite_problem(&e));
    let n: i64 = conn
        .query_row(
            "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = 'metadata'",
            [],
            |r| r.get(0),
        )
        .map_err(sql)?;
    if n == 0 {
        return Ok(None);
    }
    let mut stmt = conn
        .prepare("SELECT metadata FROM metadata ORDER BY id DESC LIMIT 1")
        .map_err(|e| bad(format!("table `metadata`: {}", sqlite_problem(&e))))?;
    let mut rows = stmt.query([]).map_err(sql)?;
    let Some(r) = rows.next().map_err(sql)? else {
        return Ok(None);
    };
    let v = r.get_ref(0).map_err(sql)?;
    text(v, "table `metadata`: metadata")
        .map(Some)
        .map_err(|e| bad(e.to_string()))
}

/// The thread body: stream the rows of the topics `ids` (sorted) in time order into `tx`. With
/// `accounted_rows`, every row is read (the payloads of other topics are not) and accounted
/// for ([`account`]); a file whose rows do not account is checked by `quick_check` at the end.
fn read_rows(
    path: PathBuf,
    ids: Vec<i64>,
    every_topic: bool,
    row_order: bool,
    accounted_rows: Option<u64>,
    tx: SyncSender<Batch>,
    back: Receiver<Rows>,
) {
    let mut last = Location::File;
    let r = (|| -> Result<(), Db3Problem> {
        let conn = open_ro(&path)?;
        let mut account = accounted_rows.and_then(RowAccount::new);
        // One scan of the time index, or of the table in its own order. Where the file has
        // topics that are not configured, SQLite tests `topic_id` on the table's row: as a
        // chain of equalities (an
        // `IN` list of more than two builds an ephemeral index probed per row, ≈ 6 % more of
        // SQLite's work); where every topic is configured, no test at all.
        let wanted = ids
            .iter()
            .map(|id| format!("topic_id = {id}"))
            .collect::<Vec<_>>()
            .join(" OR ");
        let select = "SELECT id, topic_id, timestamp,";
        // In storage order, every row is checked against the last row handed over (below).
        let order = if row_order {
            "ORDER BY id"
        } else {
            "ORDER BY timestamp, id"
        };
        let sql = if every_topic {
            format!("{select} data FROM messages {order}")
        } else if account.is_some() {
            format!("{select} CASE WHEN {wanted} THEN data END FROM messages {order}")
        } else {
            format!("{select} data FROM messages WHERE {wanted} {order}")
        };
        let mut stmt = conn.prepare(&sql).map_err(|error| Db3Problem::Sqlite {
            table: Some("messages"),
            error,
        })?;
        let mut rows = stmt.query([]).map_err(|error| Db3Problem::Sqlite {
            table: Some("messages"),
            error,
        })?;
        // A batch the reader is done with, emptied (its payload buffer kept unless a message
        // near `RECORD_LIMIT` grew it past twice `BATCH_BYTES`: memory stays that of the
        // batches in flight; the reader's empty placeholder, never allocated, is not kept), or
        // a new one.
        let new = || Rows {
            rows: Vec::with_capacity(BATCH),
            bytes: Vec::with_capacity(BATCH * BYTES_PER_ROW),
        };
        let fresh = || match back.try_recv() {
            Ok(mut r) if r.rows.capacity() >= BATCH && r.bytes.capacity() <= 2 * BATCH_BYTES => {
                r.rows.clear();
                r.bytes.clear();
                r
            }
            _ => new(),
        };
        let mut batch = fresh();
        // In storage order: the `(timestamp, id)` of the last row handed over, and the latest
        // timestamp read.
        let mut handed = (i64::MIN, i64::MIN);
        let mut latest = i64::MIN;
        while let Some(r) = rows.next().map_err(|error| {
            let after = match last {
                Location::Message(id) => Some(id),
                _ => None,
            };
            last = Location::File;
            Db3Problem::Reading { after, error }
        })? {
            let cell = |i: usize| r.get_ref(i).map_err(Db3Problem::sqlite);
            let id = int(cell(0)?, "messages.id")?;
            if let Some(a) = account.as_mut() {
                a.see(id);
            }
            let topic_id = int(cell(1)?, "messages.topic_id")?;
            // `ids` is sorted (`Part::configured_ids`); SQLite gave the payload exactly for these.
            if ids.binary_search(&topic_id).is_err() {
                continue;
            }
            last = Location::Message(id);
            let timestamp = int(cell(2)?, "messages.timestamp")?;
            if row_order {
                // Below a row already handed over: the time index's order cannot be restored.
                if timestamp < handed.0 {
                    return Err(Db3Problem::NotInRowOrder);
                }
                latest = latest.max(timestamp);
            }
            let data = match cell(3)? {
                ValueRef::Blob(b) if b.len() > RECORD_LIMIT => {
                    return Err(Db3Problem::TooLarge(b.len()));
                }
                ValueRef::Blob(b) => {
                    let start = batch.bytes.len();
                    batch.bytes.extend_from_slice(b);
                    start..batch.bytes.len()
                }
                other => {
                    return Err(Db3Problem::CellType {
                        what: "messages.data".into(),
                        expected: "a blob",
                        found: other.data_type(),
                    });
                }
            };
            batch.rows.push(Row {
                id,
                topic_id,
                timestamp,
                data,
            });
            if batch.rows.len() == BATCH || batch.bytes.len() >= BATCH_BYTES {
                let mut next = fresh();
                if row_order {
                    handed = hold_back(&mut batch, &mut next, latest.saturating_sub(HOLD_NS));
                }
                if tx
                    .send(Batch::Rows(std::mem::replace(&mut batch, next)))
                    .is_err()
                {
                    return Ok(());
                }
            }
        }
        if row_order {
            // The rest, in time order.
            batch.rows.sort_unstable_by_key(|r| (r.timestamp, r.id));
        }
        // Rows that do not account for `1..=N` (gaps left by an editing tool, or damage): the
        // file must pass SQLite's structural check after all (a damaged index reads fewer
        // rows than the table holds), and then hold as many rows as the metadata counts.
        if let Some(a) = account.as_ref().filter(|a| !a.complete()) {
            if let Some(complaint) = quick_check(&conn).map_err(Db3Problem::sqlite)? {
                last = Location::File;
                return Err(Db3Problem::Damaged(complaint));
            }
            if a.read() != a.expected() {
                last = Location::File;
                return Err(Db3Problem::Miscounted(miscounted(
                    a.expected(),
                    i64::try_from(a.read()).unwrap_or(i64::MAX),
                )));
            }
        }
        if !batch.rows.is_empty() && tx.send(Batch::Rows(batch)).is_err() {
            return Ok(());
        }
        let _ = tx.send(Batch::End);
        Ok(())
    })();
    if let Err(p) = r {
        let _ = tx.send(Batch::Err(last, p));
    }
}

/// How far back (ns) from the latest timestamp read in storage order the rows are held before
/// they are handed over: rows stored up to this much out of time order (as the receive times of
/// different topics may be) are put back into it ([`hold_back`]).
const HOLD_NS: i64 = 10_000_000;

/// Sort `batch` by `(timestamp, id)` and move the rows stamped at or after `horizon` (ns) into
/// `next` (payloads copied), unless that would leave `batch` empty; returns the `(timestamp,
/// id)` of the last row left in `batch` (the last one handed over).
///
/// Why the rows handed over are the time index's order (`ORDER BY timestamp, id`): each batch is
/// sorted, a row held back joins the next batch, and a row read afterwards is only accepted if
/// its timestamp is at least that of the last row handed over (`read_rows`; its id is larger,
/// being read later), so every row handed over follows the previous one in `(timestamp, id)`;
/// every row is handed over once. A sequence of all rows, increasing in a key unique per row, is
/// the sorted one. Which rows are held back only decides how much disorder is put right before
/// a row is refused (`Db3Problem::NotInRowOrder`), never the order handed over.
fn hold_back(batch: &mut Rows, next: &mut Rows, horizon: i64) -> (i64, i64) {
    let Rows { rows, bytes } = batch;
    rows.sort_unstable_by_key(|r| (r.timestamp, r.id));
    let cut = match rows.partition_point(|r| r.timestamp < horizon) {
        0 => rows.len(),
        k => k,
    };
    for r in rows.drain(cut..) {
        let start = next.bytes.len();
        next.bytes.extend_from_slice(&bytes[r.data.clone()]);
        next.rows.push(Row {
            data: start..next.bytes.len(),
            ..r
        });
    }
    rows.last()
        .map_or((i64::MIN, i64::MIN), |r| (r.timestamp, r.id))
}

impl Db3Reader {
    /// Open a bag: a `.db3` file, or a directory with `metadata.yaml`. The header is `header` if
    /// given, else the bag's `custom_data` key [`CUSTOM_DATA_KEY`]. Every file's tables and topics
    /// are checked here; then messages are read up to the first one (fixing the time base).
    pub fn open(
        path: &Path,
        cfg: &McapConfig,
        overrides: &ModelOverrides,
        header: Option<Header>,
    ) -> Result<Self, LogError> {
        Self::open_with(path, cfg, overrides, header, false)
    }

    /// [`Self::open`], reading each file's rows in storage order (`ORDER BY id`, one pass over
    /// the table) instead of through the time index (`ORDER BY timestamp, id`: a seek into the
    /// table per row), and putting them into time order on the way: rows are held back for
    /// [`HOLD_NS`] and sorted ([`hold_back`]), so the rows handed over are exactly the time
    /// index's sequence, and so is everything read. A row stamped before one already handed
    /// over (as one stored more than [`HOLD_NS`] out of order is; so may be one within it where
    /// a whole batch, 1,024 rows or 1 MiB, falls within [`HOLD_NS`]) stops reading with
    /// [`LogError::RowsNotInTimeOrder`] (records may have been returned before it): read the
    /// bag again with [`Self::open`]. The audit does ([`crate::open_log_in_row_order`]); a bag
    /// written by `ros2 bag record` stores its rows as they arrive, nearly in time order. (Where
    /// several rows are bad, the error may name another one than the time index would. The time
    /// index itself is not read: where the rows account for the metadata's count, a damaged
    /// index does not stop the reading, as other damage outside the rows does not.)
    pub fn open_in_row_order(
        path: &Path,
        cfg: &McapConfig,
        overrides: &ModelOverrides,
        header: Option<Header>,
    ) -> Result<Self, LogError> {
        Self::open_with(path, cfg, overrides, header, true)
    }

    fn open_with(
        path: &Path,
        cfg: &McapConfig,
        overrides: &ModelOverrides,
        header: Option<Header>,
        row_order: bool,
    ) -> Result<Self, LogError> {
        let name = path.display().to_string();
        cfg.validate()
            .map_err(|p| LogError::input(&name, Location::File, format!("invalid config: {p}")))?;
        // The metadata: the directory's metadata.yaml, or a lone file's `metadata` table.
        let (files, info, info_name, base_dir) = if path.is_dir() {
            let (info, meta_name) = read_bag_metadata(path)?;
            info.check()
                .map_err(|e| LogError::input(&meta_name, Location::File, e.to_string()))?;
            let files = bag_files(path, &info, &meta_name, "db3")?;
            (files, info, meta_name, path.to_path_buf())
        } else {
            check_size(path, &name)?;
            let info = match db_metadata(path, &name)? {
                None => BagInfo::default(),
                Some(text) => {
                    let bad = |p: String| {
                        LogError::input(&name, Location::File, format!("table `metadata`: {p}"))
                    };
                    let info = bag_info(&text, true).map_err(|e| bad(e.to_string()))?;
                    info.check().map_err(|e| bad(e.to_string()))?;
                    // One part of a split bag is not the run: audit the bag directory.
                    if info.files.len() > 1 {
                        return Err(bad(format!(
                            "this file is one of {} parts of a bag ({}): audit the bag directory (with its metadata.yaml), not one part",
                            info.files.len(),
                            info.files.join(", ")
                        )));
                    }
                    info
                }
            };
            let info_name = format!("{name} (table `metadata`)");
            (
                vec![path.to_path_buf()],
                info,
                info_name,
                crate::format::dir_of(path),
            )
        };
        let mut conv = Messages::new(&name, cfg.clone(), overrides.clone());
        // Each file's row count from the metadata (by its listed path; a lone file by the one
        // count its `metadata` table holds).
        let counted = |i: usize| -> Option<u64> {
            match info.files.get(i) {
                Some(f) if path.is_dir() => info
                    .file_counts
                    .iter()
                    .find(|(p, _)| p.trim_start_matches("./") == f.trim_start_matches("./"))
                    .map(|(_, n)| *n),
                _ => match info.file_counts.as_slice() {
                    [(_, n)] => Some(*n),
                    _ => None,
                },
            }
        };
        let parts = files
            .into_iter()
            .enumerate()
            .map(|(i, p)| open_part(p, counted(i), &mut conv))
            .collect::<Result<Vec<_>, _>>()?;
        let from_metadata = header.is_none();
        let payload_zstd = match info.messages_zstd() {
            true => Some(
                PayloadZstd::new().map_err(|p| LogError::input(&info_name, Location::File, p))?,
            ),
            false => None,
        };
        match (header, &info.pacs_header) {
            (Some(mut h), own) => {
                // The bag's own header still promises what it promises (a bag cut short stays
                // incomplete whatever header the audit is given); a malformed one is replaced.
                if let Some(own) = own
                    .as_deref()
                    .and_then(|json| custom_data_header(json, &info_name, &base_dir).ok())
                {
                    h.keep_promises_of(&own);
                    h.mark_replacing();
                }
                conv.set_header(h, Location::File)?
            }
            (None, Some(json)) => {
                let h = custom_data_header(json, &info_name, &base_dir)?;
                conv.file.clone_from(&info_name);
                conv.set_header(h, Location::File)?;
                conv.file.clone_from(&name);
            }
            (None, None) => {
                return Err(LogError::input(
                    &name,
                    Location::File,
                    format!(
                        "missing header: a rosbag2 bag carries no pacs header unless its metadata has custom_data key `{CUSTOM_DATA_KEY}` (give one: `--header FILE`, or `header=` in Python)"
                    ),
                ));
            }
        }
        let mut r = Self {
            name,
            parts,
            part: 0,
            rows: None,
            conv,
            done: false,
            current: None,
            expected: info.topic_counts,
            header_file: from_metadata.then(|| info_name.clone()),
            payload_zstd,
            info_name,
            row_order,
        };
        while r.conv.is_empty() && !r.done {
            r.pump()?;
        }
        if let (Some(h), Some(b)) = (r.conv.header.as_mut(), r.conv.base_s) {
            h.meta.insert("db3_time_base_s".into(), b.into());
        }
        Ok(r)
    }

    /// The next row of the bag (moving on to the next file at the end of one), or `None` at the
    /// end of the last file.
    fn next_row(&mut self) -> Result<Option<Row>, LogError> {
        loop {
            if let Some(rows) = self.rows.as_mut() {
                if let Some(row) = rows.batch.rows.get(rows.next) {
                    rows.next += 1;
                    return Ok(Some(row.clone()));
                }
                let part = &self.parts[self.part];
                let got = rows.rx.as_ref().map(Receiver::recv);
                match got {
                    Some(Ok(Batch::Rows(b))) => {
                        // The thread may refill the batch just read (its rows are all used).
                        let _ = rows.back.try_send(std::mem::replace(&mut rows.batch, b));
                        rows.next = 0;
                    }
                    Some(Ok(Batch::End)) => {
                        self.rows = None;
                        self.part += 1;
                    }
                    Some(Ok(Batch::Err(_, Db3Problem::NotInRowOrder))) => {
                        return Err(LogError::RowsNotInTimeOrder {
                            file: part.name.clone(),
                        });
                    }
                    Some(Ok(Batch::Err(loc, p))) => {
                        return Err(LogError::input(&part.name, loc, p.to_string()));
                    }
                    _ => {
                        return Err(LogError::input(
                            &part.name,
                            Location::File,
                            "the thread reading the messages stopped before their end",
                        ));
                    }
                }
                continue;
            }
            let Some(part) = self.parts.get(self.part) else {
                return Ok(None);
            };
            let ids = part.configured_ids();
            if ids.is_empty() {
                self.part += 1;
                continue;
            }
            let (tx, rx) = sync_channel(BATCHES_IN_FLIGHT);
            let (back, back_rx) = sync_channel(BATCHES_IN_FLIGHT);
            let path = part.path.clone();
            let accounted = part.accounted_rows;
            let every_topic = ids.len() == part.topics.len();
            let row_order = self.row_order;
            let thread = std::thread::Builder::new()
                .name("pacs-db3".into())
                .spawn(move || read_rows(path, ids, every_topic, row_order, accounted, tx, back_rx))
                .map_err(|e| LogError::Io {
                    file: part.name.clone(),
                    source: e,
                })?;
            self.rows = Some(RowStream {
                rx: Some(rx),
                back,
                batch: Rows::default(),
                next: 0,
                thread: Some(thread),
            });
        }
    }

    /// Read one row of a configured topic into the conversion (or note the end).
    fn pump(&mut self) -> Result<(), LogError> {
        let Some(row) = self.next_row()? else {
            self.done = true;
            return self.check_counts();
        };
        let part = &mut self.parts[self.part];
        let loc = Location::Message(row.id);
        let Some(i) = part.topic_index(row.topic_id) else {
            return Err(LogError::input(
                &part.name,
                loc,
                format!("topic id {} is not in table `topics`", row.topic_id),
            ));
        };
        part.topics[i].read += 1;
        let part = &self.parts[self.part];
        let (topic, stream) = (&part.topics[i].name, &part.topics[i].stream);
        // The row's payload, in the batch it came with (`next_row` moves to another batch only
        // when the next row is asked for).
        let data: &[u8] = match &self.rows {
            Some(r) => &r.batch.bytes[row.data.clone()],
            None => &[],
        };
        let what = || format!("message on `{topic}` (timestamp {} ns)", row.timestamp);
        let compressed = self.payload_zstd.is_some();
        let data = match &mut self.payload_zstd {
            Some(z) => z
                .decompress(data)
                .map_err(|p| LogError::input(&part.name, loc, format!("{}: {p}", what())))?,
            None => data,
        };
        let Ok(log_time) = u64::try_from(row.timestamp) else {
            return Err(LogError::input(
                &part.name,
                loc,
                format!("{}: negative timestamp", what()),
            ));
        };
        let m = Message {
            stream: *stream,
            topic,
            log_time,
            data,
            loc,
        };
        // The conversion names the bag; its errors name the file of the bag they are in.
        self.conv.message(m, &what).map_err(|e| {
            let e = in_file(e, &part.name);
            if compressed {
                e
            } else {
                hint_compressed(e, data)
            }
        })
    }
}

impl Db3Reader {
    /// At the end of the bag: [`check_topic_counts`] over every file's connections.
    fn check_counts(&self) -> Result<(), LogError> {
        let read = |topic: &str| {
            let files = self.parts.iter().flat_map(|p| &p.topics);
            files.filter(|t| t.name == topic).map(|t| t.read).sum()
        };
        check_topic_counts(&self.info_name, &self.expected, read, &self.conv)
    }
}

/// `e` as an error of the file `name` (a part of the bag).
fn in_file(e: LogError, name: &str) -> LogError {
    match e {
        LogError::Input {
            location, problem, ..
        } => LogError::Input {
            file: name.to_string(),
            location,
            problem,
        },
        LogError::Io { source, .. } => LogError::Io {
            file: name.to_string(),
            source,
        },
        LogError::RowsNotInTimeOrder { .. } => LogError::RowsNotInTimeOrder {
            file: name.to_string(),
        },
    }
}

/// The payloads of a bag with zstd message compression, each decompressed into one buffer.
struct PayloadZstd {
    dec: zstd::bulk::Decompressor<'static>,
    buf: Vec<u8>,
}

impl PayloadZstd {
    fn new() -> Result<Self, String> {
        Ok(Self {
            dec: zstd::bulk::Decompressor::new().map_err(|e| e.to_string())?,
            buf: Vec::new(),
        })
    }

    /// `data` (one zstd frame stating its size, at most [`RECORD_LIMIT`] bytes out) decompressed.
    fn decompress(&mut self, data: &[u8]) -> Result<&[u8], String> {
        let n = match zstd::zstd_safe::get_frame_content_size(data) {
            Ok(Some(n)) if n <= RECORD_LIMIT as u64 => n as usize,
            Ok(Some(n)) => {
                return Err(format!(
                    "the payload's zstd frame states {n} bytes, more than the limit of {RECORD_LIMIT}"
                ));
            }
            Ok(None) => {
                return Err("the payload's zstd frame does not state its size".into());
            }
            Err(_) => {
                return Err(
                    "the payload is not a zstd frame (the bag's compression_mode is `message`, compression_format `zstd`)"
                        .into(),
                );
            }
        };
        self.buf.clear();
        self.buf.reserve(n + 1);
        self.dec
            .decompress_to_buffer(data, &mut self.buf)
            .map_err(|e| format!("the payload's zstd frame cannot be decompressed: {e}"))?;
        if self.buf.len() != n {
            return Err(format!(
                "the payload's zstd frame states {n} bytes, it holds {}",
                self.buf.len()
            ));
        }
        Ok(&self.buf)
    }
}

/// A payload that starts with the zstd magic is a message-compressed bag's: say so.
fn hint_compressed(e: LogError, data: &[u8]) -> LogError {
    const ZSTD: [u8; 4] = [0x28, 0xb5, 0x2f, 0xfd];
    match e {
        LogError::Input {
            file,
            location,
            problem,
        } if data.starts_with(&ZSTD) => LogError::Input {
            file,
            location,
            problem: format!(
                "{problem} (the payload is zstd-compressed: compressed bags are not supported, decompress the bag first)"
            ),
        },
        e => e,
    }
}

impl RecordReader for Db3Reader {
    fn header(&self) -> &Header {
        // `open` fails unless the header is known.
        self.conv
            .header
            .as_ref()
            .expect("Db3Reader::open guarantees a header")
    }

    fn next_record(&mut self) -> Result<Option<Record<'_>>, LogError> {
        if let Some(p) = self.current.take() {
            self.conv.recycle(p);
        }
        loop {
            if let Some(p) = self.conv.pop_ready(self.done) {
                self.current = Some(p);
                return Ok(self
                    .current
                    .as_ref()
                    .map(|p| p.record(&self.conv.person_ids)));
            }
            if self.done {
                return Ok(None);
            }
            self.pump()?;
        }
    }

    fn location(&self) -> Location {
        self.current.as_ref().map_or(Location::File, |p| p.loc)
    }

    fn header_location(&self) -> Location {
        Location::File
    }

    fn header_file(&self) -> &str {
        self.header_file.as_deref().unwrap_or(&self.name)
    }

    fn in_canonical_order(&self) -> bool {
        // Released from the reordering window in `(t, rank, arrival)` order (`ros::Pending`).
        true
    }

    fn file(&self) -> &str {
        &self.name
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ids of the rows `read_rows` hands over for `path`, or its problem.
    fn handed(
        path: &Path,
        ids: &[i64],
        every_topic: bool,
        row_order: bool,
        accounted: Option<u64>,
    ) -> Result<Vec<i64>, String> {
        let (tx, rx) = sync_channel(BATCHES_IN_FLIGHT);
        let (back, back_rx) = sync_channel(BATCHES_IN_FLIGHT);
        let (path, ids) = (path.to_path_buf(), ids.to_vec());
        let thread = std::thread::spawn(move || {
            read_rows(path, ids, every_topic, row_order, accounted, tx, back_rx)
        });
        let mut out = Vec::new();
        let result = loop {
            match rx.recv() {
                Ok(Batch::Rows(r)) => {
                    for row in &r.rows {
                        // The payload handed with the row is the row's (its first 8 bytes
                        // are its id).
                        let b = &r.bytes[row.data.clone()];
                        assert_eq!(b.get(..8), Some(&row.id.to_le_bytes()[..]));
                        out.push(row.id);
                    }
                    let _ = back.try_send(r);
                }
                Ok(Batch::End) => break Ok(out),
                Ok(Batch::Err(_, p)) => break Err(p.to_string()),
                Err(_) => break Err("the thread stopped".into()),
            }
        };
        thread.join().unwrap();
        result
    }

    /// Row order against the time index, on 60 random files read by the real reading thread:
    /// 300 to 4,000 rows on three topics (one, two or all three configured; accounted or not,
    /// so each of the three queries), receive times 0 to 2 ms apart with runs of equal ones,
    /// stored in the order of each time moved by up to ±`jitter` (0 to 30 ms), payloads of 16
    /// to 300 bytes and some of 200 kB (batches cut by their bytes). Through the time index the
    /// rows handed over are `ORDER BY timestamp, id` of the configured topics; in row order they
    /// are that sequence too, or reading stops with the row-order problem, which never happens
    /// within ±4 ms (no run of equal times fills a batch here).
    #[test]
    fn read_rows_in_row_order_hands_over_the_time_index_sequence() {
        let mut next_u = pacs_testkit::xorshift(0x51f1_5e4d_2b3c_7a19);
        let dir = std::env::temp_dir().join(format!("pacs-db3-rows-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (mut refused, mut same) = (0, 0);
        for case in 0..60 {
            let n = 300 + (next_u() % 3_701) as usize;
            let jitter = [0i64, 1, 4, 12, 30][case % 5] * 1_000_000;
            let mut times = Vec::with_capacity(n);
            let mut ts = 1_700_000_000_000_000_000i64;
            for _ in 0..n {
                if !next_u().is_multiple_of(4) {
                    ts += (next_u() % 2_000_001) as i64;
                }
                times.push(ts);
            }
            let mut stored: Vec<(i64, usize)> = times
                .iter()
                .enumerate()
                .map(|(i, &t)| {
                    let moved = if jitter > 0 {
                        (next_u() % (2 * jitter as u64 + 1)) as i64 - jitter
                    } else {
                        0
                    };
                    (t + moved, i)
                })
                .collect();
            stored.sort_unstable();
            let path = dir.join(format!("case{case}.db3"));
            let _ = std::fs::remove_file(&path);
            let c = Connection::open(&path).unwrap();
            c.execute_batch(
                "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, \
                 timestamp INTEGER NOT NULL, data BLOB NOT NULL); \
                 CREATE INDEX timestamp_idx ON messages (timestamp ASC); BEGIN;",
            )
            .unwrap();
            for (k, &(_, i)) in stored.iter().enumerate() {
                let id = k as i64 + 1;
                let len = if next_u().is_multiple_of(400) {
                    200_000
                } else {
                    16 + (next_u() % 285) as usize
                };
                let mut data = vec![0u8; len];
                data[..8].copy_from_slice(&id.to_le_bytes());
                let topic = 1 + (next_u() % 3) as i64;
                c.execute(
                    "INSERT INTO messages VALUES (?1, ?2, ?3, ?4)",
                    rusqlite::params![id, topic, times[i], data],
                )
                .unwrap();
            }
            c.execute_batch("COMMIT;").unwrap();
            let ids: Vec<i64> = match case % 3 {
                0 => vec![1, 2, 3],
                1 => vec![1, 3],
                _ => vec![2],
            };
            let every = ids.len() == 3;
            let list = ids
                .iter()
                .map(i64::to_string)
                .collect::<Vec<_>>()
                .join(", ");
            let expected: Vec<i64> = c
                .prepare(&format!(
                    "SELECT id FROM messages WHERE topic_id IN ({list}) ORDER BY timestamp, id"
                ))
                .unwrap()
                .query_map([], |r| r.get(0))
                .unwrap()
                .map(Result::unwrap)
                .collect();
            drop(c);
            let accounted = (case % 2 == 0).then_some(n as u64);
            let by_index = handed(&path, &ids, every, false, accounted).unwrap();
            assert_eq!(by_index, expected, "case {case}: through the time index");
            match handed(&path, &ids, every, true, accounted) {
                Ok(by_rows) => {
                    same += 1;
                    assert_eq!(by_rows, expected, "case {case}: in row order");
                }
                Err(p) => {
                    refused += 1;
                    assert_eq!(p, Db3Problem::NotInRowOrder.to_string(), "case {case}");
                    assert!(jitter > 4_000_000, "case {case}: refused at ±{jitter} ns");
                }
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
        assert!(same >= 30 && refused >= 1, "same {same}, refused {refused}");
    }

    /// `hold_back` over 2,000 random batches (timestamps a few ms apart and jittered, some
    /// equal; payloads naming their row): the rows left are sorted by `(timestamp, id)`, all
    /// before the horizon unless none is (then all are left), each payload still its row's; the
    /// rows moved are exactly the others, after them, with their payloads; the key returned is
    /// the last row left's.
    #[test]
    fn hold_back_hands_over_sorted_rows_before_the_horizon() {
        let mut next_u = pacs_testkit::xorshift(0x2545_f491_4f6c_dd1d);
        for case in 0..2_000 {
            let n = 1 + (next_u() % 64) as usize;
            let mut batch = Rows::default();
            let mut next = Rows::default();
            let mut latest = i64::MIN;
            for id in 0..n as i64 {
                let ts = id * 1_000_000 + (next_u() % 30_000_000) as i64 - 15_000_000;
                let ts = if next_u().is_multiple_of(8) { 0 } else { ts };
                latest = latest.max(ts);
                let start = batch.bytes.len();
                batch.bytes.extend_from_slice(&id.to_le_bytes());
                batch.rows.push(Row {
                    id,
                    topic_id: 1,
                    timestamp: ts,
                    data: start..batch.bytes.len(),
                });
            }
            let horizon = latest - (next_u() % 40_000_000) as i64;
            let key = hold_back(&mut batch, &mut next, horizon);
            let payload = |r: &Rows, row: &Row| {
                i64::from_le_bytes(r.bytes[row.data.clone()].try_into().unwrap())
            };
            let keys = |r: &Rows| -> Vec<(i64, i64)> {
                r.rows.iter().map(|x| (x.timestamp, x.id)).collect()
            };
            let (left, moved) = (keys(&batch), keys(&next));
            assert!(!left.is_empty(), "case {case}");
            assert_eq!(left.len() + moved.len(), n, "case {case}");
            let mut all = [left.clone(), moved.clone()].concat();
            all.sort_unstable();
            all.dedup_by_key(|k| k.1);
            assert_eq!(all.len(), n, "case {case}: a row lost or repeated");
            assert!(
                left.windows(2).all(|w| w[0] < w[1]),
                "case {case}: {left:?}"
            );
            assert!(moved.windows(2).all(|w| w[0] < w[1]), "case {case}");
            if let (Some(a), Some(b)) = (left.last(), moved.first()) {
                assert!(a < b, "case {case}");
            }
            if moved.is_empty() {
                // Nothing held back: every row before the horizon, or none (then all go).
                let before = left.iter().filter(|k| k.0 < horizon).count();
                assert!(before == 0 || before == n, "case {case}: {before} of {n}");
            } else {
                assert!(left.iter().all(|k| k.0 < horizon), "case {case}");
                assert!(moved.iter().all(|k| k.0 >= horizon), "case {case}");
            }
            assert_eq!(Some(&key), left.last(), "case {case}");
            for r in [&batch, &next] {
                for row in &r.rows {
                    assert_eq!(payload(r, row), row.id, "case {case}");
                }
            }
        }
    }
}
