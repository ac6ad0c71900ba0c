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
}

/// Parse rosbag2 metadata YAML (aliases refused, nesting and size bounded): `metadata.yaml` has it
/// under `rosbag2_bagfile_information`; a `metadata` table holds it bare (`bare` accepts both).
/// Errors say what is wrong; the caller names the file.
pub(super) fn bag_info(text: &str, bare: bool) -> Result<BagInfo, String> {
    use yaml_rust2::parser::{Event, Parser};
    use yaml_rust2::{Yaml, YamlLoader};
    // First pass over the events: no aliases (a loader expands them, which can blow up), bounded
    // depth; then the loader builds the document.
    let mut p = Parser::new_from_str(text);
    let mut depth = 0usize;
    loop {
        let (ev, mark) = p.next_token().map_err(|e| format!("invalid YAML: {e}"))?;
        match ev {
            Event::StreamEnd => break,
            Event::Alias(_) => {
                return Err(format!(
                    "line {}: YAML aliases are not supported",
                    mark.line()
                ));
            }
            Event::SequenceStart(..) | Event::MappingStart(..) => {
                depth += 1;
                if depth > YAML_DEPTH {
                    return Err(format!(
                        "line {}: nested deeper than {YAML_DEPTH} levels",
                        mark.line()
                    ));
                }
            }
            Event::SequenceEnd | Event::MappingEnd => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    let docs = YamlLoader::load_from_str(text).map_err(|e| format!("invalid YAML: {e}"))?;
    let [doc] = docs.as_slice() else {
        return Err(format!("{} YAML documents, expected one", docs.len()));
    };
    let info = match &doc["rosbag2_bagfile_information"] {
        i @ Yaml::Hash(_) => i,
        _ if bare && matches!(doc, Yaml::Hash(_)) => doc,
        _ => return Err("no mapping `rosbag2_bagfile_information`".into()),
    };
    let text_of = |key: &str| -> Result<String, String> {
        match &info[key] {
            Yaml::BadValue | Yaml::Null => Ok(String::new()),
            Yaml::String(s) => Ok(s.clone()),
            other => Err(format!(
                "rosbag2_bagfile_information.{key}: expected a string, found {other:?}"
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
                    return Err(format!(
                        "rosbag2_bagfile_information.relative_file_paths[{i}]: expected a string, found {f:?}"
                    ));
                };
                files.push(s.clone());
            }
        }
        other => {
            return Err(format!(
                "rosbag2_bagfile_information.relative_file_paths: expected a list, found {other:?}"
            ));
        }
    }
    let pacs_header = match &info["custom_data"] {
        Yaml::BadValue | Yaml::Null => None,
        Yaml::Hash(h) => match h.get(&Yaml::String(CUSTOM_DATA_KEY.into())) {
            None => None,
            Some(Yaml::String(s)) => Some(s.clone()),
            Some(other) => {
                return Err(format!(
                    "rosbag2_bagfile_information.custom_data.{CUSTOM_DATA_KEY}: expected a string (the header's JSON text), found {other:?}"
                ));
            }
        },
        other => {
            return Err(format!(
                "rosbag2_bagfile_information.custom_data: expected a mapping, found {other:?}"
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
                    return Err(format!("{field}.topic_metadata.name: expected a string"));
                };
                let count = match &t["message_count"] {
                    Yaml::Integer(c) if *c >= 0 => *c as u64,
                    other => {
                        return Err(format!(
                            "{field}.message_count: expected a count (integer ≥ 0), found {other:?}"
                        ));
                    }
                };
                topic_counts.push((name.clone(), count));
            }
        }
        other => {
            return Err(format!(
                "rosbag2_bagfile_information.topics_with_message_count: expected a list, found {other:?}"
            ));
        }
    }
    Ok(BagInfo {
        topic_counts,
        storage,
        files,
        compression_format: text_of("compression_format")?,
        compression_mode: text_of("compression_mode")?,
        pacs_header,
    })
}

impl BagInfo {
    /// Refuse what this reader does not read: another storage, compression.
    pub(super) fn check(&self) -> Result<(), String> {
        if let Some(s) = self.storage.as_deref().filter(|s| *s != "sqlite3") {
            return Err(format!(
                "storage_identifier `{s}` is not supported here (expected `sqlite3`){}",
                if s == "mcap" {
                    "; audit the bag's .mcap file itself"
                } else {
                    ""
                }
            ));
        }
        let mode = self.compression_mode.to_ascii_lowercase();
        if !(mode.is_empty() || mode == "none") || !self.compression_format.is_empty() {
            return Err(format!(
                "compressed bags are not supported (compression_mode `{}`, compression_format `{}`): decompress the bag first (e.g. `ros2 bag convert` to an uncompressed bag)",
                self.compression_mode, self.compression_format
            ));
        }
        Ok(())
    }
}
