//! The JSON Lines reader reads most lines in place, in its input's buffer; lines across the
//! buffer's end, blank lines, lines with bytes outside ASCII and lines the fast scanner does not
//! take are copied out and read as before. Whatever the buffer's size, and so wherever the lines
//! fall in it, the reader gives the same records, the same line numbers and the same errors.

use pacs_log::jsonl::JsonlReader;
use pacs_log::{LogError, RecordReader};
use std::io::BufReader;

const HEADER: &str = "{\"type\": \"header\", \"format\": \"pacs-log\", \"version\": 1, \"robot\": \"fr3\", \"human\": \"default\", \"constraints\": \"sorting\"}\n";

/// Records of every kind, written as pacs writes them and otherwise (spaces, CRLF, escapes,
/// text outside ASCII, blank lines, a shield record with nested diagnostics).
const BODY: &[&str] = &[
    "{\"type\":\"event\",\"t\":0.0,\"name\":\"episode_start\"}\n",
    "{\"type\":\"human\",\"t\":0.0,\"t_meas\":0.0,\"positions\":[[1.8,0.2,1.4],[1.8,-0.2,0.9]]}\n",
    "{\"type\":\"robot\",\"t\":0.001,\"q\":[0.012002984195271257,-0.7848432820745567,-0.0005283976453661861,-2.352341624880035,-0.013630849591725966,1.561103065746978,0.77970376188577],\"dq\":[-7.061073045433511e-5,2.9805773898642442e-5,0.0,0,-0,1e-300,5e-324],\"ddq\":[-0.14122146090867022,0.059611547797284885,0.04419561259462412,1,2,3,4]}\n",
    "{\"binding\":{\"body_part\":0,\"constrained\":true,\"energy\":0.0119,\"kind\":\"pfl\",\"link\":6,\"threshold\":0.01},\"contact_energy\":0.0119,\"on_failsafe\":true,\"t\":0.001,\"type\":\"shield\",\"verified\":false}\n",
    "\n",
    "   \n",
    "{\"type\":\"object\",\"t\":0.002,\"t_meas\":0.0015,\"id\":\"sphere-b\",\"position\":[0.47393131955634177,-0.380406300279194,0.04728062528461232],\"velocity\":[-0.0029595973326424756,0.0785904491975051,-0.012240240762220795]}\n",
    "  { \"type\" : \"robot\" , \"t\" : 2E-3 , \"q\" : [ 1 , 2.5e-3 , 3, 4, 5, 6, 7 ] }  \r\n",
    "{\"type\":\"event\",\"t\":0.003,\"name\":\"caf\u{e9} \u{2014} pause\"}\n",
    "{\"type\":\"event\",\"t\":0.003,\"name\":\"esc\\u0041ped\\n\"}\n",
    "{\"type\":\"robot\",\"t\":0.004,\"q\":[1.0e0,2,3,4,5,6,7.000000000000000000001]}\n",
];

/// Every record's `Debug` text with its line, then the error or the end.
fn read_all(text: &[u8], capacity: usize) -> Vec<String> {
    let mut out = Vec::new();
    let mut r = match JsonlReader::new("t.jsonl", BufReader::with_capacity(capacity, text)) {
        Ok(r) => r,
        Err(e) => return vec![format!("header error: {e}")],
    };
    loop {
        match r.next_record() {
            Ok(Some(rec)) => {
                let rec = format!("{rec:?}");
                out.push(format!("{rec} at {:?}", r.location()));
            }
            Ok(None) => {
                out.push("end".into());
                return out;
            }
            Err(e) => {
                let kind = match &e {
                    LogError::Io { .. } => "io",
                    _ => "input",
                };
                out.push(format!("{kind} error: {e}"));
                return out;
            }
        }
    }
}

fn log_of(lines: &[&[u8]]) -> Vec<u8> {
    let mut text = HEADER.as_bytes().to_vec();
    for l in lines {
        text.extend_from_slice(l);
    }
    text
}

/// Buffer sizes from one byte (every line copied) past the longest line (most read in place).
const CAPACITIES: &[usize] = &[1, 2, 3, 7, 8, 13, 31, 64, 100, 199, 257, 400, 1000, 1 << 16];

fn agree_at_every_capacity(text: &[u8]) -> Vec<String> {
    let reference = read_all(text, 1);
    for &c in CAPACITIES {
        assert_eq!(read_all(text, c), reference, "capacity {c}");
    }
    reference
}

#[test]
fn every_buffer_size_reads_the_same_records() {
    let lines: Vec<&[u8]> = BODY.iter().map(|l| l.as_bytes()).collect();
    let records = agree_at_every_capacity(&log_of(&lines));
    // Nine records and the end: blank lines are skipped, every other line is a record.
    assert_eq!(records.len(), 10, "{records:#?}");
    assert_eq!(records.last().map(String::as_str), Some("end"));
    assert!(records[6].contains("café — pause"), "{}", records[6]);
    assert!(records[7].contains("escAped\\n"), "{}", records[7]);
    // Line numbers count the header and the blank lines: the object record is line 8.
    assert!(records[4].contains("Line(8)"), "{}", records[4]);
    assert!(records[8].contains("Line(12)"), "{}", records[8]);
}

#[test]
fn errors_are_the_same_at_every_buffer_size() {
    let good: Vec<&[u8]> = BODY.iter().map(|l| l.as_bytes()).collect();
    let bad_lines: &[&[u8]] = &[
        // Not UTF-8 inside a string, and outside.
        b"{\"type\":\"event\",\"t\":0.5,\"name\":\"a\xff\"}\n",
        b"{\"type\":\"event\",\"t\":0.5,\"name\":\"a\"}\xc3\n",
        // Not JSON, a record without a field it needs, a field twice, an unknown field.
        b"{\"type\":\"robot\",\"t\":0.5,\"q\":[1,2,3,4,5,6,]}\n",
        b"{\"type\":\"robot\",\"t\":0.5}\n",
        b"{\"type\":\"robot\",\"t\":0.5,\"t\":0.6,\"q\":[1,2,3,4,5,6,7]}\n",
        b"{\"type\":\"robot\",\"t\":0.5,\"q\":[1,2,3,4,5,6,7],\"qq\":[]}\n",
        // A last line without its newline (a writer stopped mid-line).
        b"{\"type\":\"robot\",\"t\":0.5,\"q\":[1,2,3,4,5,6,7]}",
        b"{\"type\":\"robot\",\"t\":0.5,\"q\":[1,2,3,4,5,6,7.5",
    ];
    for (k, bad) in bad_lines.iter().enumerate() {
        for at in [0, 3, good.len()] {
            let mut lines = good.clone();
            lines.insert(at, bad);
            let records = agree_at_every_capacity(&log_of(&lines));
            let last = records.last().unwrap();
            assert!(
                last.starts_with("input error"),
                "bad line {k} at {at}: {last}"
            );
            // The error names the bad line: the header is line 1, blank lines count.
            let line_no = 2 + lines[..at].len();
            assert!(
                last.contains(&format!("line {line_no}")),
                "bad line {k} at {at}: {last}"
            );
        }
    }
}
