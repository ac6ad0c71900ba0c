//! A rosbag2 bag's metadata (`metadata.yaml`, or a `.db3` file's `metadata` table): parsed with
//! YAML aliases refused and nesting bounded, and checked for what this reader reads (storage,
//! compression).

use super::CUSTOM_DATA_KEY;

/// Deepest nesting of `metadata.yaml` accepted.
const YAML_DEPTH: usize = 32;

/// The settings of a bag found in its metadata (`metadata.yaml` or a `metadata` table).
#[derive(Debug, Default)]
pub(super) struct BagInfo {
    pub(super) storage: Option<String>,
    pub(super) files: Vec<String>,
    pub(super) compression_format: String,
    pub(super) compression_mode: String,
    pub(super) pacs_header: Option<String>,
    /// `topics_with_message_count`: messages per topic name, as the recorder counted them.
    pub(super) topic_counts: Vec<(String, u64)>,
    /// Rows of `messages` per file, as the recorder counted them (every topic): `files[i]`'s
    /// `message_count` by `path`, or the bag's `message_count` when it has one file. Only what is
    /// well formed; a file without a count here is checked by SQLite's `quick_check` instead.
    pub(super) file_counts: Vec<(String, u64)>,
}

/// Why a bag's metadata is refused (the caller names the file).
#[derive(Debug, thiserror::Error)]
pub(super) enum MetadataError {
    #[error("invalid YAML: {0}")]
    Yaml(#[from] yaml_rust2::ScanError),
    #[error("line {0}: YAML aliases are not supported")]
    Alias(usize),
    #[error("line {0}: nested deeper than {YAML_DEPTH} levels")]
    TooDeep(usize),
    #[error("{0} YAML documents, expected one")]
    Documents(usize),
    #[error("no mapping `rosbag2_bagfile_information`")]
    NoInformation,
    /// `field` holds a value of the wrong kind (`found`: the value as parsed, if one was).
    #[error("{field}: expected {expected}{}", found.as_deref().map(|f| format!(", found {f}")).unwrap_or_default())]
    WrongType {
        field: String,
        expected: &'static str,
        found: Option<String>,
    },
    #[error("storage_identifier `{storage}` is not supported here (expected `sqlite3`){}", if storage == "mcap" { "; `pacs_log::open_log` reads MCAP bags" } else { "" })]
    Storage { storage: String },
    #[error(
        "compressed bags are not supported (compression_mode `{mode}`, compression_format `{format}`; of the compressed forms only `message` with `zstd` is read): decompress the bag first (e.g. `ros2 bag convert` to an uncompressed bag)"
    )]
    Compressed { mode: String, format: String },
    /// Two statements of the metadata contradict each other.
    #[error("the metadata contradicts itself: {0}")]
    Contradiction(String),
}

/// A value of the wrong kind at `field`.
fn wrong(
    field: impl Into<String>,
    expected: &'static str,
    found: Option<&yaml_rust2::Yaml>,
) -> MetadataError {
    MetadataError::WrongType {
        field: field.into(),
        expected,
        found: found.map(|f| format!("{f:?}")),
    }
}

/// Parse rosbag2 metadata YAML (aliases refused, nesting and size bounded): `metadata.yaml` has it
/// under `rosbag2_bagfile_information`; a `metadata` table holds it bare (`bare` accepts both).
/// Errors say what is wrong; the caller names the file.
pub(super) fn bag_info(text: &str, bare: bool) -> Result<BagInfo, MetadataError> {
    use yaml_rust2::parser::{Event, Parser};
    use yaml_rust2::{Yaml, YamlLoader};
    // First pass over the events: no aliases (a loader expands them, which can blow up), bounded
    // depth; then the loader builds the document.
    let mut p = Parser::new_from_str(text);
    let mut depth = 0usize;
    loop {
        let (ev, mark) = p.next_token()?;
        match ev {
            Event::StreamEnd => break,
            Event::Alias(_) => {
                return Err(MetadataError::Alias(mark.line()));
            }
            Event::SequenceStart(..) | Event::MappingStart(..) => {
                depth += 1;
                if depth > YAML_DEPTH {
                    return Err(MetadataError::TooDeep(mark.line()));
                }
            }
            Event::SequenceEnd | Event::MappingEnd => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    let docs = YamlLoader::load_from_str(text)?;
    let [doc] = docs.as_slice() else {
        return Err(MetadataError::Documents(docs.len()));
    };
    let info = match &doc["rosbag2_bagfile_information"] {
        i @ Yaml::Hash(_) => i,
        _ if bare && matches!(doc, Yaml::Hash(_)) => doc,
        _ => return Err(MetadataError::NoInformation),
    };
    let text_of = |key: &str| -> Result<String, MetadataError> {
        match &info[key] {
            Yaml::BadValue | Yaml::Null => Ok(String::new()),
            Yaml::String(s) => Ok(s.clone()),
            other => Err(wrong(
                format!("rosbag2_bagfile_information.{key}"),
                "a string",
                Some(other),
            )),
        }
    };
    let storage = Some(text_of("storage_identifier")?).filter(|s| !s.is_empty());
    let mut files = Vec::new();
    match &info["relative_file_paths"] {
        Yaml::BadValue | Yaml::Null => {}
        Yaml::Array(a) => {
            for (i, f) in a.iter().enumerate() {
                let Yaml::String(s) = f else {
                    return Err(wrong(
                        format!("rosbag2_bagfile_information.relative_file_paths[{i}]"),
                        "a string",
                        Some(f),
                    ));
                };
                // `./a.db3` and `a.db3` name one file.
                let same = |f: &String| f.trim_start_matches("./") == s.trim_start_matches("./");
                if let Some(j) = files.iter().position(same) {
                    return Err(MetadataError::Contradiction(format!(
                        "relative_file_paths[{i}] `{s}` is relative_file_paths[{j}] again (a part read twice)"
                    )));
                }
                files.push(s.clone());
            }
        }
        other => {
            return Err(wrong(
                "rosbag2_bagfile_information.relative_file_paths",
                "a list",
                Some(other),
            ));
        }
    }
    let pacs_header = match &info["custom_data"] {
        Yaml::BadValue | Yaml::Null => None,
        Yaml::Hash(h) => match h.get(&Yaml::String(CUSTOM_DATA_KEY.into())) {
            None => None,
            Some(Yaml::String(s)) => Some(s.clone()),
            Some(other) => {
                return Err(wrong(
                    format!("rosbag2_bagfile_information.custom_data.{CUSTOM_DATA_KEY}"),
                    "a string (the header's JSON text)",
                    Some(other),
                ));
            }
        },
        other => {
            return Err(wrong(
                "rosbag2_bagfile_information.custom_data",
                "a mapping",
                Some(other),
            ));
        }
    };
    let mut topic_counts = Vec::new();
    match &info["topics_with_message_count"] {
        Yaml::BadValue | Yaml::Null => {}
        Yaml::Array(a) => {
            for (i, t) in a.iter().enumerate() {
                let field = format!("rosbag2_bagfile_information.topics_with_message_count[{i}]");
                let Yaml::String(name) = &t["topic_metadata"]["name"] else {
                    return Err(wrong(
                        format!("{field}.topic_metadata.name"),
                        "a string",
                        None,
                    ));
                };
                let count = match &t["message_count"] {
                    Yaml::Integer(c) if *c >= 0 => *c as u64,
                    other => {
                        return Err(wrong(
                            format!("{field}.message_count"),
                            "a count (integer ≥ 0)",
                            Some(other),
                        ));
                    }
                };
                topic_counts.push((name.clone(), count));
            }
        }
        other => {
            return Err(wrong(
                "rosbag2_bagfile_information.topics_with_message_count",
                "a list",
                Some(other),
            ));
        }
    }
    // Per-file row counts (rosbag2 metadata version ≥ 5 and `rosbags` write `files`): a count
    // that is not a count is passed over (then the file is checked by `quick_check`); a count
    // is checked against the file's rows (`open_part`, `read_rows`).
    let mut file_counts = Vec::new();
    if let Yaml::Array(a) = &info["files"] {
        for f in a {
            if let (Yaml::String(path), Yaml::Integer(c)) = (&f["path"], &f["message_count"])
                && *c >= 0
            {
                file_counts.push((path.clone(), *c as u64));
            }
        }
    }
    // The per-file statements must describe the files the bag lists (a part taken out of
    // relative_file_paths but still in `files` is a recording cut short), and add up to the
    // bag's message count.
    if let Yaml::Array(a) = &info["files"] {
        let plain = |p: &str| p.trim_start_matches("./").to_string();
        let mut described: Vec<String> = Vec::new();
        for (i, f) in a.iter().enumerate() {
            if let Yaml::String(path) = &f["path"] {
                if !files.iter().any(|f| plain(f) == plain(path)) {
                    return Err(MetadataError::Contradiction(format!(
                        "files[{i}].path `{path}` is not in relative_file_paths ({})",
                        files.join(", ")
                    )));
                }
                if let Some(j) = described.iter().position(|d| *d == plain(path)) {
                    return Err(MetadataError::Contradiction(format!(
                        "files[{i}].path `{path}` is files[{j}].path again (a part described twice)"
                    )));
                }
                described.push(plain(path));
            }
        }
    }
    if let Yaml::Integer(total) = &info["message_count"]
        && !file_counts.is_empty()
        && file_counts.len() == files.len()
    {
        let sum: u64 = file_counts.iter().map(|(_, c)| c).sum();
        if i64::try_from(sum).ok() != Some(*total) {
            return Err(MetadataError::Contradiction(format!(
                "message_count {total}, while its files' message_count add up to {sum}"
            )));
        }
    }
    if file_counts.is_empty()
        && let ([only], Yaml::Integer(c)) = (files.as_slice(), &info["message_count"])
        && *c >= 0
    {
        file_counts.push((only.clone(), *c as u64));
    }
    Ok(BagInfo {
        file_counts,
        topic_counts,
        storage,
        files,
        compression_format: text_of("compression_format")?,
        compression_mode: text_of("compression_mode")?,
        pacs_header,
    })
}

impl BagInfo {
    /// Refuse what this reader does not read: another storage, compression (but for zstd
    /// message compression, [`BagInfo::messages_zstd`]).
    pub(super) fn check(&self) -> Result<(), MetadataError> {
        if let Some(s) = self.storage.as_deref().filter(|s| *s != "sqlite3") {
            return Err(MetadataError::Storage {
                storage: s.to_string(),
            });
        }
        if self.messages_zstd() {
            return Ok(());
        }
        self.check_compression()
    }

    /// Whether each message's payload is zstd-compressed on its own (rosbag2's
    /// `compression_mode: message` with `compression_format: zstd`).
    pub(super) fn messages_zstd(&self) -> bool {
        self.compression_mode.eq_ignore_ascii_case("message")
            && self.compression_format.eq_ignore_ascii_case("zstd")
    }

    /// Refuse a compressed bag (rosbag2's file or message compression).
    pub(super) fn check_compression(&self) -> Result<(), MetadataError> {
        let mode = self.compression_mode.to_ascii_lowercase();
        if !(mode.is_empty() || mode == "none") || !self.compression_format.is_empty() {
            return Err(MetadataError::Compressed {
                mode: self.compression_mode.clone(),
                format: self.compression_format.clone(),
            });
        }
        Ok(())
    }
}
