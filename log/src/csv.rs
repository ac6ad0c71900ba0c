//! Streaming reader of the CSV form of log formats v1 and v2 (see `docs/log-format.md`):
//! line 1 is `#` followed by the JSON header; then one record per line:
//! `robot,t,n,q_1..q_n[,dq_1..dq_n[,ddq_1..ddq_n]]`, `human,t,t_meas,x_1,y_1,z_1,...` (v2:
//! `human,t,t_meas,id,x_1,...`), `event,t,name`,
//! `shield,t,...`. Blank lines and lines starting with `#` after the header are skipped.

use crate::error::{Location, LogError};
use crate::format::{Header, Record, RecordReader};
use std::io::BufRead;

/// Largest joint count `n` a robot row may give (far above any model's; a larger `n` is refused
/// before any arithmetic on it).
const MAX_JOINTS: usize = 1024;

/// Streaming CSV log reader; buffers are reused, so reading allocates nothing per robot sample.
pub struct CsvReader<R: BufRead> {
    file: String,
    input: R,
    line: String,
    line_no: u64,
    header: Header,
    q: Vec<f64>,
    dq: Vec<f64>,
    ddq: Vec<f64>,
    positions: Vec<[f64; 3]>,
    name: String,
}

/// A cell that is not a finite number; `field` is its field path (`q[2]`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
enum CellError {
    #[error("{field}: `{text}` is not a number")]
    NotANumber { field: String, text: String },
    #[error("{field}: value {value} is not finite")]
    NotFinite { field: String, value: f64 },
}

fn num(field: &str, s: &str) -> Result<f64, CellError> {
    let v: f64 = s.trim().parse().map_err(|_| CellError::NotANumber {
        field: field.into(),
        text: s.trim().into(),
    })?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(CellError::NotFinite {
            field: field.into(),
            value: v,
        })
    }
}

impl<R: BufRead> CsvReader<R> {
    /// Read and check the `#`-prefixed JSON header on the first line.
    pub fn new(file: &str, mut input: R) -> Result<Self, LogError> {
        let mut line = String::new();
        let n = input.read_line(&mut line).map_err(|e| LogError::Io {
            file: file.into(),
            source: e,
        })?;
        let loc = Location::Line(1);
        if n == 0 {
            return Err(LogError::input(
                file,
                Location::File,
                "missing header: the file is empty",
            ));
        }
        if line.starts_with('\u{feff}') {
            return Err(LogError::input(
                file,
                loc,
                "the file starts with a UTF-8 byte order mark (EF BB BF); CSV logs are UTF-8 without BOM: remove it",
            ));
        }
        let Some(json) = line.trim().strip_prefix('#') else {
            return Err(LogError::input(
                file,
                loc,
                "missing header: the first line must be `#` followed by the JSON header",
            ));
        };
        let header = Header::checked(file, loc, serde_json::from_str(json))?;
        Ok(Self {
            file: file.into(),
            input,
            line,
            line_no: 1,
            header,
            q: Vec::new(),
            dq: Vec::new(),
            ddq: Vec::new(),
            positions: Vec::new(),
            name: String::new(),
        })
    }
}

impl<R: BufRead> RecordReader for CsvReader<R> {
    fn header(&self) -> &Header {
        &self.header
    }
    fn file(&self) -> &str {
        &self.file
    }
    fn location(&self) -> Location {
        Location::Line(self.line_no)
    }

    fn next_record(&mut self) -> Result<Option<Record<'_>>, LogError> {
        loop {
            self.line.clear();
            let n = self.input.read_line(&mut self.line).map_err(|e| {
                if e.kind() == std::io::ErrorKind::InvalidData {
                    LogError::input(
                        &self.file,
                        Location::Line(self.line_no + 1),
                        "line is not valid UTF-8",
                    )
                } else {
                    LogError::Io {
                        file: self.file.clone(),
                        source: e,
                    }
                }
            })?;
            if n == 0 {
                return Ok(None);
            }
            self.line_no += 1;
            let t = self.line.trim();
            if !t.is_empty() && !t.starts_with('#') {
                break;
            }
        }
        let loc = Location::Line(self.line_no);
        let file = self.file.as_str();
        let err = |p: String| LogError::input(file, loc, p);
        let bad = |p: CellError| LogError::input(file, loc, p.to_string());
        if !self.line.ends_with('\n') {
            return Err(err(
                "truncated line (no newline at the end of the file)".into()
            ));
        }
        let mut cells = self.line.trim_end_matches(['\n', '\r']).split(',');
        let kind = cells.next().unwrap_or("").trim();
        // The `t_meas` column of measurement rows (human, object).
        let t_meas_cell = |cells: &mut std::str::Split<'_, char>| -> Result<f64, LogError> {
            num(
                "t_meas",
                cells
                    .next()
                    .ok_or_else(|| err("missing column `t_meas`".into()))?,
            )
            .map_err(bad)
        };
        let t = num(
            "t",
            cells
                .next()
                .ok_or_else(|| err("missing column `t`".into()))?,
        )
        .map_err(bad)?;
        match kind {
            "robot" => {
                let n_cell = cells
                    .next()
                    .ok_or_else(|| err("missing column `n`".into()))?;
                let n: usize = n_cell
                    .trim()
                    .parse()
                    .map_err(|_| err(format!("n: `{}` is not a joint count", n_cell.trim())))?;
                if n > MAX_JOINTS {
                    return Err(err(format!(
                        "n: {n} joints is more than any robot model holds (at most {MAX_JOINTS})"
                    )));
                }
                self.q.clear();
                self.dq.clear();
                self.ddq.clear();
                for (i, c) in cells.enumerate() {
                    if i < n {
                        self.q.push(num(&format!("q[{i}]"), c).map_err(bad)?);
                    } else if i < 2 * n {
                        self.dq
                            .push(num(&format!("dq[{}]", i - n), c).map_err(bad)?);
                    } else {
                        self.ddq
                            .push(num(&format!("ddq[{}]", i - 2 * n), c).map_err(bad)?);
                    }
                }
                if self.q.len() != n
                    || (!self.dq.is_empty() && self.dq.len() != n)
                    || (!self.ddq.is_empty() && self.ddq.len() != n)
                {
                    return Err(err(format!(
                        "robot row: expected {n}, {} or {} values after n = {n}, found {}",
                        2 * n,
                        3 * n,
                        self.q.len() + self.dq.len() + self.ddq.len()
                    )));
                }
                Ok(Some(Record::Robot {
                    t,
                    q: &self.q,
                    dq: (!self.dq.is_empty()).then_some(&self.dq[..]),
                    ddq: (!self.ddq.is_empty()).then_some(&self.ddq[..]),
                }))
            }
            "human" => {
                let t_meas = t_meas_cell(&mut cells)?;
                // Version 2 rows name the person: `human,t,t_meas,id,x_1,...`.
                let person = if self.header.version >= 2 {
                    self.name.clear();
                    self.name.push_str(
                        cells
                            .next()
                            .ok_or_else(|| err("missing column `id` (the person id)".into()))?
                            .trim(),
                    );
                    true
                } else {
                    false
                };
                self.positions.clear();
                let mut p = [0.0; 3];
                let mut k = 0;
                for (i, c) in cells.enumerate() {
                    p[i % 3] = num(&format!("positions[{}][{}]", i / 3, i % 3), c).map_err(bad)?;
                    k = i + 1;
                    if k % 3 == 0 {
                        self.positions.push(p);
                    }
                }
                if k % 3 != 0 {
                    return Err(err(format!(
                        "human row: {k} coordinates is not a multiple of 3"
                    )));
                }
                Ok(Some(Record::Human {
                    t,
                    t_meas,
                    person: person.then_some(self.name.as_str()),
                    positions: &self.positions,
                }))
            }
            "event" => {
                self.name.clear();
                self.name.push_str(
                    cells
                        .next()
                        .ok_or_else(|| err("missing column `name`".into()))?
                        .trim(),
                );
                Ok(Some(Record::Event {
                    t,
                    name: &self.name,
                }))
            }
            "object" => {
                let t_meas = t_meas_cell(&mut cells)?;
                self.name.clear();
                self.name.push_str(
                    cells
                        .next()
                        .ok_or_else(|| err("missing column `id`".into()))?
                        .trim(),
                );
                let mut v = [0.0; 6];
                let mut k = 0;
                for (i, c) in cells.enumerate() {
                    if i >= 6 {
                        return Err(err(
                            "object row: more than 6 values after the id (x,y,z[,vx,vy,vz])".into(),
                        ));
                    }
                    let field = if i < 3 { "position" } else { "velocity" };
                    v[i] = num(&format!("{field}[{}]", i % 3), c).map_err(bad)?;
                    k = i + 1;
                }
                if k != 3 && k != 6 {
                    return Err(err(format!(
                        "object row: expected 3 (position) or 6 (position, velocity) values after the id, found {k}"
                    )));
                }
                Ok(Some(Record::Object {
                    t,
                    t_meas,
                    id: &self.name,
                    position: [v[0], v[1], v[2]],
                    velocity: (k == 6).then_some([v[3], v[4], v[5]]),
                }))
            }
            "shield" => Ok(Some(Record::Shield { t })),
            other => Err(err(format!("unknown record type `{other}`"))),
        }
    }
}
