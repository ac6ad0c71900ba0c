//! Opening a log by its form: MCAP, ROS 2 sqlite3 bag, CSV or JSON Lines, one reader behind
//! [`RecordReader`].

use crate::error::{Location, LogError};
use crate::format::{Header, ModelOverrides, RecordReader};
use crate::mcap::McapConfig;
use std::io::Read;
use std::path::Path;

/// Refuse a path that is neither a regular file nor a directory (a FIFO, a socket, a device):
/// opening a FIFO blocks until a writer comes, which would stall an audit for ever.
pub(crate) fn regular_or_dir(path: &Path) -> Result<(), LogError> {
    let meta = std::fs::metadata(path).map_err(|e| LogError::Io {
        file: path.display().to_string(),
        source: e,
    })?;
    if meta.is_file() || meta.is_dir() {
        return Ok(());
    }
    Err(LogError::input(
        &path.display().to_string(),
        Location::File,
        "not a regular file (a FIFO, socket or device): a log is a file or a bag directory",
    ))
}

/// The first `n` bytes of `path` (fewer if the file is shorter); errors name the file.
fn prefix(path: &Path, n: u64) -> Result<Vec<u8>, LogError> {
    let io = |e| LogError::Io {
        file: path.display().to_string(),
        source: e,
    };
    regular_or_dir(path)?;
    let f = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::with_capacity(n as usize);
    f.take(n).read_to_end(&mut bytes).map_err(io)?;
    Ok(bytes)
}

/// Whether `path` is an MCAP file: its name ends in `.mcap` (without opening it) or it starts
/// with the MCAP magic. Errors: the file cannot be opened or read.
pub fn is_mcap(path: &Path) -> Result<bool, LogError> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
    {
        return Ok(true);
    }
    Ok(crate::mcap::has_magic(&prefix(path, 8)?))
}

/// Whether `path` is read as JSON Lines by [`open_log`]: a file that is neither MCAP
/// ([`is_mcap`]) nor a sqlite3 bag ([`is_db3`]) nor named `*.csv`. Errors: the file cannot be
/// opened or read.
pub fn is_jsonl(path: &Path) -> Result<bool, LogError> {
    Ok(!path.is_dir()
        && !path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
        && !is_mcap(path)?
        && !is_db3(path)?)
}

/// Whether `path` takes a header given apart from it (`pacs audit --header`): an MCAP log or a
/// ROS 2 bag (a bag directory, a `.db3`), whose recording may carry no pacs header; JSON Lines
/// and CSV logs carry their own. The one rule for the CLI and Python's `pacs.fleet.audit`.
/// Errors: the file cannot be opened or read.
pub fn takes_header(path: &Path) -> Result<bool, LogError> {
    Ok(path.is_dir() || is_mcap(path)? || is_db3(path)?)
}

/// Whether `path` is a ROS 2 sqlite3 bag: a directory with `metadata.yaml`, a file whose name ends
/// in `.db3`, or a file that starts with the SQLite magic (another directory is not). A bag
/// directory counts whatever its storage (the metadata is not read here): [`open_log`] reads one
/// in the MCAP storage as MCAP ([`crate::db3::mcap_bag`]). Errors: the file cannot be opened or
/// read.
pub fn is_db3(path: &Path) -> Result<bool, LogError> {
    if crate::db3::is_bag_dir(path)
        || path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("db3"))
    {
        return Ok(true);
    }
    if path.is_dir() {
        return Ok(false);
    }
    Ok(crate::db3::has_magic(&prefix(path, 16)?))
}

/// Open a log for reading by its form: a ROS 2 sqlite3 bag ([`is_db3`]), MCAP ([`is_mcap`]),
/// CSV if the name ends in `.csv`, JSON Lines otherwise. `mcap` and `overrides` configure the
/// ROS readers; `header` is a separate pacs header (`--header`), which only MCAP logs and bags
/// accept (for them it replaces the recorded one; for other logs it is an error).
///
/// Guarantee: the one reader selection of every caller (audit, CLI, Python); the path as given
/// names the log in every error. A directory that is not a bag is refused.
pub fn open_log(
    path: &Path,
    mcap: &McapConfig,
    overrides: &ModelOverrides,
    header: Option<&Header>,
) -> Result<Box<dyn RecordReader>, LogError> {
    open_log_with(path, mcap, overrides, header, false)
}

/// [`open_log`], with a sqlite3 bag's rows read in storage order while that is time order
/// ([`crate::db3::Db3Reader::open_in_row_order`]: one pass over each file's table instead of a
/// seek per row through its time index; the same records). A bag whose rows are not stored in
/// time order ends with [`LogError::RowsNotInTimeOrder`], possibly after some records: the
/// caller then reads it again from the start with [`open_log`] (as `pacs_audit::audit_file`
/// does). Every other log is read exactly as by [`open_log`].
pub fn open_log_in_row_order(
    path: &Path,
    mcap: &McapConfig,
    overrides: &ModelOverrides,
    header: Option<&Header>,
) -> Result<Box<dyn RecordReader>, LogError> {
    open_log_with(path, mcap, overrides, header, true)
}

/// Read the log at `path` with `read`, as the audit does: first opened in the table's own order
/// ([`open_log_in_row_order`]); where a sqlite3 bag refuses that order (`read` fails with an
/// error `refused` recognizes: [`LogError::RowsNotInTimeOrder`] inside `E`), `read` runs again
/// from the start on the log opened through its time index ([`open_log`]), so it must start
/// afresh (a new auditor, a new output file). The one place that decides which order a log is
/// read in for the audit and its scene.
pub fn read_log<T, E: From<LogError>>(
    path: &Path,
    mcap: &McapConfig,
    overrides: &ModelOverrides,
    header: Option<&Header>,
    mut read: impl FnMut(&mut dyn RecordReader) -> Result<T, E>,
    refused: impl Fn(&E) -> bool,
) -> Result<T, E> {
    let in_row_order = open_log_in_row_order(path, mcap, overrides, header)
        .map_err(E::from)
        .and_then(|mut reader| read(reader.as_mut()));
    match in_row_order {
        Err(e) if refused(&e) => {
            let mut reader = open_log(path, mcap, overrides, header)?;
            read(reader.as_mut())
        }
        r => r,
    }
}

fn open_log_with(
    path: &Path,
    mcap: &McapConfig,
    overrides: &ModelOverrides,
    header: Option<&Header>,
    row_order: bool,
) -> Result<Box<dyn RecordReader>, LogError> {
    let name = path.display().to_string();
    regular_or_dir(path)?;
    if path.is_dir() && !crate::db3::is_bag_dir(path) {
        return Err(LogError::input(
            &name,
            Location::File,
            format!(
                "a directory without {}: not a ROS 2 bag (give log files)",
                crate::db3::METADATA_FILE
            ),
        ));
    }
    if let Some(bag) = crate::db3::mcap_bag(path)? {
        return open_mcap_bag(bag, mcap, overrides, header);
    }
    // A ROS recording's file may be one part of a split bag (JSON Lines and CSV logs never are).
    if !path.is_dir()
        && (is_db3(path)? || is_mcap(path)?)
        && let Some(dir) = crate::db3::refuse_one_part(path)?
    {
        // The bag's only part, described by the metadata beside it: read as that bag.
        return open_log_with(&dir, mcap, overrides, header, row_order);
    }
    if is_db3(path)? {
        let header = header.cloned();
        return Ok(Box::new(if row_order {
            crate::db3::Db3Reader::open_in_row_order(path, mcap, overrides, header)?
        } else {
            crate::db3::Db3Reader::open(path, mcap, overrides, header)?
        }));
    }
    let mcap_log = is_mcap(path)?;
    let f = std::fs::File::open(path).map_err(|e| LogError::Io {
        file: name.clone(),
        source: e,
    })?;
    let input = std::io::BufReader::with_capacity(1 << 16, f);
    if mcap_log {
        return Ok(Box::new(crate::mcap::McapReader::new(
            &name,
            input,
            mcap,
            overrides,
            header.cloned(),
        )?));
    }
    if header.is_some() {
        return Err(LogError::input(
            &name,
            Location::File,
            "a separate header (--header) applies to MCAP logs and ROS 2 bags only; this log carries its own",
        ));
    }
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
    {
        Ok(Box::new(crate::csv::CsvReader::new(&name, input)?))
    } else {
        Ok(Box::new(crate::jsonl::JsonlReader::new(&name, input)?))
    }
}

/// A rosbag2 bag directory in the MCAP storage ([`crate::db3::mcap_bag`]): its files read one
/// after the other as one log ([`crate::mcap::McapReader::new_parts`]), with the header given
/// (`--header`), else the metadata's `custom_data` one, else the first file's `pacs` metadata
/// record.
fn open_mcap_bag(
    bag: crate::db3::McapBag,
    mcap: &McapConfig,
    overrides: &ModelOverrides,
    header: Option<&Header>,
) -> Result<Box<dyn RecordReader>, LogError> {
    let mut parts = Vec::with_capacity(bag.files.len());
    for f in &bag.files {
        let name = f.display().to_string();
        let file = std::fs::File::open(f).map_err(|e| LogError::Io {
            file: name.clone(),
            source: e,
        })?;
        parts.push((name, std::io::BufReader::with_capacity(1 << 16, file)));
    }
    // The given header replaces the metadata's, keeping the promises it makes (a bag cut short
    // stays incomplete whatever header it is audited with; a malformed one is replaced).
    let (header, header_file) = match header {
        Some(h) => {
            let mut h = h.clone();
            if let Ok(Some(own)) = bag.header() {
                h.keep_promises_of(&own);
                h.mark_replacing();
            }
            (Some(h), None)
        }
        None => match bag.header()? {
            Some(h) => (Some(h), Some(bag.metadata.as_str())),
            None => (None, None),
        },
    };
    let mut r = crate::mcap::McapReader::new_parts(parts, mcap, overrides, header, header_file)?;
    r.expect_topic_counts(&bag.metadata, bag.topic_counts)?;
    Ok(Box::new(r))
}
