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
    #[error("{field}: empty cell (a trailing comma, or a value left out?)")]
    Empty { field: String },
    #[error("{field}: value {value} is not finite")]
    NotFinite { field: String, value: f64 },
}

fn num(field: &str, s: &str) -> Result<f64, CellError> {
    if s.trim().is_empty() {
        return Err(CellError::Empty {
            field: field.into(),
        });
    }
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
        if !self.next_data_line()? {
            return Ok(None);
        }
        let row = Row {
            file: self.file.as_str(),
            loc: Location::Line(self.line_no),
        };
        if !self.line.ends_with('\n') {
            return Err(row.err("truncated line (no newline at the end of the file)".into()));
        }
        let mut cells = self.line.trim_end_matches(['\n', '\r']).split(',');
        let kind = cells.next().unwrap_or("").trim();
        let t = num(
            "t",
            cells
                .next()
                .ok_or_else(|| row.err("missing column `t`".into()))?,
        )
        .map_err(|e| row.bad(e))?;
        match kind {
            "robot" => {
                robot_values(&mut cells, &row, &mut self.q, &mut self.dq, &mut self.ddq)?;
                Ok(Some(Record::Robot {
                    t,
                    q: &self.q,
                    dq: (!self.dq.is_empty()).then_some(&self.dq[..]),
                    ddq: (!self.ddq.is_empty()).then_some(&self.ddq[..]),
                }))
            }
            "human" => {
                let t_meas = t_meas_cell(&mut cells, &row)?;
                // Version 2 rows name the person: `human,t,t_meas,id,x_1,...`.
                let person = if self.header.version >= 2 {
                    self.name.clear();
                    self.name.push_str(
                        cells
                            .next()
                            .ok_or_else(|| row.err("missing column `id` (the person id)".into()))?
                            .trim(),
                    );
                    true
                } else {
                    false
                };
                human_positions(&mut cells, &row, &mut self.positions).map_err(|e| {
                    // A number where the id belongs: the id is likely missing.
                    match e {
                        LogError::Input { problem, .. }
                            if person && self.name.parse::<f64>().is_ok() =>
                        {
                            row.err(format!(
                                "{problem}: the person id `{}` is a number; a version 2 human row is `human,t,t_meas,id,x,y,z,…` (is the id missing?)",
                                self.name
                            ))
                        }
                        e => e,
                    }
                })?;
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
                        .ok_or_else(|| row.err("missing column `name`".into()))?
                        .trim(),
                );
                // `event,t,name` and nothing after it (as the JSON record: a name with more
                // after it is not the name; `event,1.0,end,x` is no `end` event).
                if let Some(extra) = cells.next() {
                    return Err(row.err(format!(
                        "event row has a cell after `name`: `{}` (an event row is `event,t,name`)",
                        extra.trim()
                    )));
                }
                Ok(Some(Record::Event {
                    t,
                    name: &self.name,
                }))
            }
            "object" => {
                let t_meas = t_meas_cell(&mut cells, &row)?;
                self.name.clear();
                self.name.push_str(
                    cells
                        .next()
                        .ok_or_else(|| row.err("missing column `id`".into()))?
                        .trim(),
                );
                let (v, k) = object_values(&mut cells, &row)?;
                Ok(Some(Record::Object {
                    t,
                    t_meas,
                    id: &self.name,
                    position: [v[0], v[1], v[2]],
                    velocity: (k == 6).then_some([v[3], v[4], v[5]]),
                }))
            }
            "shield" => Ok(Some(Record::Shield { t })),
            other => Err(row.err(format!("unknown record type `{other}`"))),
        }
    }
}

impl<R: BufRead> CsvReader<R> {
    /// Read the next line that holds a record into `line` (blank lines and `#` comments
    /// skipped); false at the end of the file.
    fn next_data_line(&mut self) -> Result<bool, LogError> {
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
                return Ok(false);
            }
            self.line_no += 1;
            let t = self.line.trim();
            if !t.is_empty() && !t.starts_with('#') {
                return Ok(true);
            }
        }
    }
}

/// The row being read: errors name the file and the line.
struct Row<'a> {
    file: &'a str,
    loc: Location,
}

impl Row<'_> {
    /// A problem with the row.
    fn err(&self, p: String) -> LogError {
        LogError::input(self.file, self.loc, p)
    }

    /// A cell of the row that is not a finite number.
    fn bad(&self, p: CellError) -> LogError {
        LogError::input(self.file, self.loc, p.to_string())
    }
}

/// The cells of a row after its kind.
type Cells<'a> = std::str::Split<'a, char>;

/// The `t_meas` column of measurement rows (human, object).
fn t_meas_cell(cells: &mut Cells<'_>, row: &Row<'_>) -> Result<f64, LogError> {
    num(
        "t_meas",
        cells
            .next()
            .ok_or_else(|| row.err("missing column `t_meas`".into()))?,
    )
    .map_err(|e| row.bad(e))
}

/// A robot row's values after `t`: the joint count `n`, then `n` positions and, optionally, `n`
/// velocities and `n` accelerations (into `q`, `dq`, `ddq`; empty where not given).
fn robot_values(
    cells: &mut Cells<'_>,
    row: &Row<'_>,
    q: &mut Vec<f64>,
    dq: &mut Vec<f64>,
    ddq: &mut Vec<f64>,
) -> Result<(), LogError> {
    let n_cell = cells
        .next()
        .ok_or_else(|| row.err("missing column `n`".into()))?;
    let n: usize = n_cell
        .trim()
        .parse()
        .map_err(|_| row.err(format!("n: `{}` is not a joint count", n_cell.trim())))?;
    if n > MAX_JOINTS {
        return Err(row.err(format!(
            "n: {n} joints is more than any robot model holds (at most {MAX_JOINTS})"
        )));
    }
    q.clear();
    dq.clear();
    ddq.clear();
    for (i, c) in cells.enumerate() {
        if i < n {
            q.push(num(&format!("q[{i}]"), c).map_err(|e| row.bad(e))?);
        } else if i < 2 * n {
            dq.push(num(&format!("dq[{}]", i - n), c).map_err(|e| row.bad(e))?);
        } else {
            ddq.push(num(&format!("ddq[{}]", i - 2 * n), c).map_err(|e| row.bad(e))?);
        }
    }
    if q.len() != n || (!dq.is_empty() && dq.len() != n) || (!ddq.is_empty() && ddq.len() != n) {
        return Err(row.err(format!(
            "robot row: expected {n}, {} or {} values after n = {n}, found {}",
            2 * n,
            3 * n,
            q.len() + dq.len() + ddq.len()
        )));
    }
    Ok(())
}

/// A human row's keypoint coordinates (x, y, z per keypoint) into `positions`.
fn human_positions(
    cells: &mut Cells<'_>,
    row: &Row<'_>,
    positions: &mut Vec<[f64; 3]>,
) -> Result<(), LogError> {
    positions.clear();
    let mut p = [0.0; 3];
    let mut k = 0;
    for (i, c) in cells.enumerate() {
        p[i % 3] = num(&format!("positions[{}][{}]", i / 3, i % 3), c).map_err(|e| row.bad(e))?;
        k = i + 1;
        if k % 3 == 0 {
            positions.push(p);
        }
    }
    if k % 3 != 0 {
        return Err(row.err(format!("human row: {k} coordinates is not a multiple of 3")));
    }
    Ok(())
}

/// An object row's values after the id: the position and, optionally, the velocity; returns
/// them and their count (3 or 6).
fn object_values(cells: &mut Cells<'_>, row: &Row<'_>) -> Result<([f64; 6], usize), LogError> {
    let mut v = [0.0; 6];
    let mut k = 0;
    for (i, c) in cells.enumerate() {
        if i >= 6 {
            return Err(
                row.err("object row: more than 6 values after the id (x,y,z[,vx,vy,vz])".into())
            );
        }
        let field = if i < 3 { "position" } else { "velocity" };
        v[i] = num(&format!("{field}[{}]", i % 3), c).map_err(|e| row.bad(e))?;
        k = i + 1;
    }
    if k != 3 && k != 6 {
        return Err(row.err(format!(
            "object row: expected 3 (position) or 6 (position, velocity) values after the id, found {k}"
        )));
    }
    Ok((v, k))
}
