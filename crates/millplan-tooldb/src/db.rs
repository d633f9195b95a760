//! The tool library: one SQLite file in WAL mode, created and migrated on open,
//! every write a transaction, decisions in an append-only log.

use rusqlite::{
    params, Connection, ErrorCode, OptionalExtension, Transaction, TransactionBehavior,
};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// How long a command waits for another program that is writing to the library.
pub const BUSY_TIMEOUT: Duration = Duration::from_secs(10);

/// Schema migrations; `PRAGMA user_version` is the number applied.
const MIGRATIONS: &[&str] = &[
    // 1: tools, ISO 13399 properties, inserts, measurements, pallets, event log.
    r#"
    CREATE TABLE tools (
        number   INTEGER PRIMARY KEY CHECK (number >= 0),
        name     TEXT NOT NULL DEFAULT '',
        kind     TEXT NOT NULL DEFAULT 'mill',
        l        REAL NOT NULL DEFAULT 0,
        r        REAL NOT NULL DEFAULT 0,
        dl       REAL NOT NULL DEFAULT 0,
        dr       REAL NOT NULL DEFAULT 0,
        ltol     REAL NOT NULL DEFAULT 0,
        rtol     REAL NOT NULL DEFAULT 0,
        lbreak   REAL NOT NULL DEFAULT 0,
        rbreak   REAL NOT NULL DEFAULT 0,
        locked   INTEGER NOT NULL DEFAULT 0,
        sister   INTEGER,
        life_min REAL,
        used_min REAL NOT NULL DEFAULT 0,
        measured INTEGER NOT NULL DEFAULT 0
    );
    CREATE TABLE tool_props (
        tool   INTEGER NOT NULL REFERENCES tools(number) ON DELETE CASCADE,
        symbol TEXT NOT NULL,
        value  TEXT NOT NULL,
        PRIMARY KEY (tool, symbol)
    );
    CREATE TABLE inserts (
        id          INTEGER PRIMARY KEY,
        tool        INTEGER NOT NULL REFERENCES tools(number) ON DELETE CASCADE,
        designation TEXT NOT NULL,
        insl        REAL,
        tp          REAL
    );
    CREATE TABLE presetter (
        id   INTEGER PRIMARY KEY,
        tool INTEGER NOT NULL REFERENCES tools(number) ON DELETE CASCADE,
        time TEXT NOT NULL,
        l    REAL NOT NULL,
        r    REAL NOT NULL
    );
    CREATE TABLE measurements (
        id        INTEGER PRIMARY KEY,
        tool      INTEGER NOT NULL REFERENCES tools(number) ON DELETE CASCADE,
        time      TEXT NOT NULL,
        kind      TEXT NOT NULL CHECK (kind IN ('first', 'inspection')),
        l         REAL,
        r         REAL,
        per_tooth TEXT,
        pz        REAL
    );
    CREATE TABLE pallets (
        id     TEXT PRIMARY KEY,
        locked INTEGER NOT NULL DEFAULT 0
    );
    CREATE TABLE events (
        id       INTEGER PRIMARY KEY,
        time     TEXT NOT NULL,
        tool     INTEGER,
        decision TEXT NOT NULL,
        reason   TEXT NOT NULL,
        inputs   TEXT NOT NULL,
        outcome  TEXT NOT NULL
    );
    CREATE TRIGGER events_no_update BEFORE UPDATE ON events
        BEGIN SELECT RAISE(ABORT, 'the event log is append-only'); END;
    CREATE TRIGGER events_no_delete BEFORE DELETE ON events
        BEGIN SELECT RAISE(ABORT, 'the event log is append-only'); END;
    "#,
];

/// What went wrong with the library. Only [`DbError::UnknownTool`] means a row
/// is genuinely absent; every other variant is a failure to report.
#[derive(Debug, thiserror::Error)]
pub enum DbError {
    #[error("{}", sql_message(.0))]
    Sql(#[from] rusqlite::Error),
    /// The file system refused (creating the library's folder).
    #[error("{}: {source}", .path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("the database has schema version {found}; this millplan knows up to {known}: use a newer millplan")]
    NewerSchema { found: i64, known: i64 },
    /// A row that does not fit the schema (a text where a number belongs, a log
    /// entry that is not JSON): the file was damaged or written by another program.
    #[error("{0}: the library holds data this millplan cannot read (damaged, or changed by another program)")]
    Damaged(String),
    #[error("no tool {0} in the library")]
    UnknownTool(u32),
    #[error("{0}")]
    Invalid(String),
}

impl DbError {
    /// Whether the fault lies in what the user gave: arguments and values, or a
    /// file that is not a tool library this millplan can read (not a database,
    /// damaged, from a newer millplan). Otherwise the system refused (a lock held
    /// by another program, a read-only file, an I/O error, a full disk) or
    /// millplan itself is wrong (a constraint its own writes broke).
    pub fn is_bad_input(&self) -> bool {
        match self {
            DbError::Sql(e) => matches!(
                e.sqlite_error_code(),
                Some(ErrorCode::NotADatabase | ErrorCode::DatabaseCorrupt)
            ),
            DbError::Io { .. } => false,
            DbError::NewerSchema { .. }
            | DbError::Damaged(_)
            | DbError::UnknownTool(_)
            | DbError::Invalid(_) => true,
        }
    }
}

/// SQLite's message, with what it means for a tool library when that helps.
fn sql_message(e: &rusqlite::Error) -> String {
    let hint = match e.sqlite_error_code() {
        Some(ErrorCode::DatabaseBusy | ErrorCode::DatabaseLocked) => format!(
            "another program is writing to the library (waited {} s); try again when it is done",
            BUSY_TIMEOUT.as_secs()
        ),
        Some(ErrorCode::ReadOnly) => "the file or its folder is not writable".into(),
        Some(ErrorCode::NotADatabase) => "this is not a millplan tool library".into(),
        Some(ErrorCode::DatabaseCorrupt) => "the file is damaged; restore a copy".into(),
        Some(ErrorCode::CannotOpen) => {
            "check that its folder exists and is writable, and that FILE-wal and FILE-shm are not folders".into()
        }
        _ => String::new(),
    };
    if hint.is_empty() {
        e.to_string()
    } else {
        format!("{e}: {hint}")
    }
}

/// A tool as the library keeps it (mm, minutes).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ToolRecord {
    pub number: u32,
    #[serde(default)]
    pub name: String,
    #[serde(default = "default_kind")]
    pub kind: String,
    #[serde(default)]
    pub l: f64,
    #[serde(default)]
    pub r: f64,
    #[serde(default)]
    pub dl: f64,
    #[serde(default)]
    pub dr: f64,
    #[serde(default)]
    pub ltol: f64,
    #[serde(default)]
    pub rtol: f64,
    #[serde(default)]
    pub lbreak: f64,
    #[serde(default)]
    pub rbreak: f64,
    #[serde(default)]
    pub locked: bool,
    #[serde(default)]
    pub sister: Option<u32>,
    #[serde(default)]
    pub life_min: Option<f64>,
    #[serde(default)]
    pub used_min: f64,
    #[serde(default)]
    pub measured: bool,
    /// ISO 13399 properties by symbol (INSL, TP, IC, DC, …); unknown symbols survive.
    #[serde(default)]
    pub iso: BTreeMap<String, String>,
}

fn default_kind() -> String {
    "mill".into()
}

/// Changes to a tool record: what is given replaces, what is not stays.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ToolEdit {
    pub name: Option<String>,
    pub kind: Option<String>,
    pub l: Option<f64>,
    pub r: Option<f64>,
    pub ltol: Option<f64>,
    pub rtol: Option<f64>,
    pub lbreak: Option<f64>,
    pub rbreak: Option<f64>,
    pub sister: Option<u32>,
    /// Tool life, minutes.
    pub life_min: Option<f64>,
    /// Insert length INSL and thread pitch TP (thread mills), mm.
    pub insl: Option<f64>,
    pub tp: Option<f64>,
    /// Any ISO 13399 property, symbol and value.
    pub iso: Vec<(String, String)>,
}

impl ToolRecord {
    /// Applies `e`; refuses insert data whose PZ cannot be formed (the record
    /// is then unchanged).
    pub fn apply(&mut self, e: ToolEdit) -> Result<(), crate::thread::ThreadError> {
        let mut t = self.clone();
        if let Some(v) = e.name {
            t.name = v;
        }
        if let Some(v) = e.kind {
            t.kind = v;
        }
        for (slot, v) in [
            (&mut t.l, e.l),
            (&mut t.r, e.r),
            (&mut t.ltol, e.ltol),
            (&mut t.rtol, e.rtol),
            (&mut t.lbreak, e.lbreak),
            (&mut t.rbreak, e.rbreak),
        ] {
            if let Some(v) = v {
                *slot = v;
            }
        }
        if e.sister.is_some() {
            t.sister = e.sister;
        }
        if e.life_min.is_some() {
            t.life_min = e.life_min;
        }
        if let Some(v) = e.insl {
            t.iso.insert("INSL".into(), v.to_string());
        }
        if let Some(v) = e.tp {
            t.iso.insert("TP".into(), v.to_string());
        }
        for (k, v) in e.iso {
            t.iso.insert(k, v);
        }
        if let (Some(l), Some(p)) = (t.iso.get("INSL"), t.iso.get("TP")) {
            if let (Ok(l), Ok(p)) = (l.parse::<f64>(), p.parse::<f64>()) {
                crate::thread::pz(l, p)?;
            }
        }
        *self = t;
        Ok(())
    }

    pub fn new(number: u32, name: &str) -> ToolRecord {
        ToolRecord {
            number,
            name: name.into(),
            kind: default_kind(),
            l: 0.0,
            r: 0.0,
            dl: 0.0,
            dr: 0.0,
            ltol: 0.0,
            rtol: 0.0,
            lbreak: 0.0,
            rbreak: 0.0,
            locked: false,
            sister: None,
            life_min: None,
            used_min: 0.0,
            measured: false,
            iso: BTreeMap::new(),
        }
    }

    /// Effective radius R + DR (what a sister tool must match).
    pub fn effective_r(&self) -> f64 {
        self.r + self.dr
    }

    pub fn validate(&self) -> Result<(), DbError> {
        let nums = [
            self.l,
            self.r,
            self.dl,
            self.dr,
            self.ltol,
            self.rtol,
            self.lbreak,
            self.rbreak,
            self.used_min,
        ];
        if nums.iter().any(|v| !v.is_finite())
            || self.life_min.map(|v| !v.is_finite()).unwrap_or(false)
        {
            return Err(DbError::Invalid(format!(
                "tool {}: a value is not a finite number",
                self.number
            )));
        }
        if self.l < 0.0
            || self.r < 0.0
            || self.ltol < 0.0
            || self.rtol < 0.0
            || self.lbreak < 0.0
            || self.rbreak < 0.0
        {
            return Err(DbError::Invalid(format!(
                "tool {}: L, R and the tolerances must not be negative",
                self.number
            )));
        }
        if self.sister == Some(self.number) {
            return Err(DbError::Invalid(format!(
                "tool {} cannot be its own sister tool",
                self.number
            )));
        }
        Ok(())
    }
}

/// One decision of the log.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct EventRecord {
    pub id: i64,
    pub time: String,
    pub tool: Option<u32>,
    pub decision: String,
    pub reason: String,
    pub inputs: serde_json::Value,
    pub outcome: serde_json::Value,
}

/// The library.
pub struct ToolDb {
    conn: Connection,
}

/// Now as an ISO 8601 UTC timestamp (seconds and milliseconds since the epoch,
/// formatted without a date library).
pub fn now() -> String {
    let d = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap_or_default();
    let secs = d.as_secs() as i64;
    let (days, rem) = (secs.div_euclid(86400), secs.rem_euclid(86400));
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days + 719468;
    let era = z.div_euclid(146097);
    let doe = z - era * 146097;
    let yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + if month <= 2 { 1 } else { 0 };
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}.{:03}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60,
        d.subsec_millis()
    )
}

impl ToolDb {
    /// Opens (creating and migrating as needed) the library at `path`.
    ///
    /// `path` is always a file name: never SQLite's `:memory:` nor a `file:` URI,
    /// which would silently give a library that is not saved where asked. A library
    /// from a newer millplan is refused before anything is written to it.
    pub fn open(path: &Path) -> Result<ToolDb, DbError> {
        Self::open_with_timeout(path, BUSY_TIMEOUT)
    }

    /// [`ToolDb::open`] waiting at most `busy` for another program's write lock.
    pub fn open_with_timeout(path: &Path, busy: Duration) -> Result<ToolDb, DbError> {
        if path.as_os_str().is_empty() {
            return Err(DbError::Invalid("the library path is empty".into()));
        }
        if path.is_dir() {
            return Err(DbError::Invalid("is a folder, not a library file".into()));
        }
        // A device, FIFO or socket is no library: SQLite would open it and
        // create its journal beside it (`/dev/null-wal`).
        if std::fs::metadata(path).is_ok_and(|m| !m.is_file()) {
            return Err(DbError::Invalid(
                "not a regular file (a device, a FIFO or a socket): the library is an SQLite file"
                    .into(),
            ));
        }
        // A mistyped folder is an error, not a tree of new folders (the
        // caller creates the default library's folder).
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            if !dir.is_dir() {
                return Err(DbError::Invalid(format!(
                    "the folder {} does not exist",
                    dir.display()
                )));
            }
        }
        // SQLite gives special meaning to `:memory:` and `file:…` URIs; `./:memory:`
        // and `./file:…` are plain file names. Absolute paths start with `/`.
        let file = if path.is_relative() {
            Path::new(".").join(path)
        } else {
            path.to_path_buf()
        };
        // A library the user may not write is opened read-only: it can be
        // shown and exported; a change is refused by SQLite.
        let read_only = path.is_file()
            && std::fs::OpenOptions::new()
                .append(true)
                .open(path)
                .is_err_and(|e| e.kind() == std::io::ErrorKind::PermissionDenied);
        if read_only {
            return Self::open_read_only(&file, busy);
        }
        let conn = Connection::open(file)?;
        Self::setup(conn, busy)
    }

    /// Opens a library read-only, as it is: first sharing SQLite's locks,
    /// else (no `-shm` file and a folder that may not be written either)
    /// as an unchanging file.
    fn open_read_only(file: &Path, busy: Duration) -> Result<ToolDb, DbError> {
        use rusqlite::OpenFlags;
        let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        let shared = Connection::open_with_flags(file, flags).and_then(|c| {
            version(&c).map_err(|_| rusqlite::Error::InvalidQuery)?;
            Ok(c)
        });
        let conn = match shared {
            Ok(c) => c,
            Err(_) => {
                let enc: String = file
                    .to_string_lossy()
                    .chars()
                    .map(|c| match c {
                        '%' | '?' | '#' => format!("%{:02X}", c as u32),
                        c => c.to_string(),
                    })
                    .collect();
                let uri = format!("file:{enc}?immutable=1");
                Connection::open_with_flags(uri, flags | OpenFlags::SQLITE_OPEN_URI)?
            }
        };
        conn.busy_timeout(busy)?;
        if Self::check_version(&conn)? != MIGRATIONS.len() as i64 {
            return Err(DbError::Invalid(
                "a read-only library of an older version: it must be written to be brought up to date".into(),
            ));
        }
        conn.execute_batch("PRAGMA foreign_keys=ON;")?;
        Ok(ToolDb { conn })
    }

    /// An in-memory library (tests, benchmarks).
    pub fn memory() -> Result<ToolDb, DbError> {
        Self::setup(Connection::open_in_memory()?, BUSY_TIMEOUT)
    }

    fn setup(conn: Connection, busy: Duration) -> Result<ToolDb, DbError> {
        conn.busy_timeout(busy)?;
        // Refuse a newer library before switching it to WAL (which rewrites its header).
        Self::check_version(&conn)?;
        // WAL: readers never block the writer; a killed process loses at most the
        // transaction it was in. synchronous=NORMAL keeps every committed
        // transaction across a process crash (not across a power cut).
        let _: String = conn.query_row("PRAGMA journal_mode=WAL", [], |r| r.get(0))?;
        conn.execute_batch("PRAGMA synchronous=NORMAL; PRAGMA foreign_keys=ON;")?;
        let mut db = ToolDb { conn };
        db.migrate()?;
        Ok(db)
    }

    pub fn schema_version(&self) -> Result<i64, DbError> {
        version(&self.conn)
    }

    fn check_version(conn: &Connection) -> Result<i64, DbError> {
        let found = version(conn)?;
        let known = MIGRATIONS.len() as i64;
        if found > known {
            return Err(DbError::NewerSchema { found, known });
        }
        Ok(found)
    }

    fn migrate(&mut self) -> Result<(), DbError> {
        // Up to date: no write lock (a read-only library stays readable).
        if Self::check_version(&self.conn)? == MIGRATIONS.len() as i64 {
            return Ok(());
        }
        // Two programs opening a new library at once must not both create its
        // tables: the version is read again under the write lock.
        let tx = self.write()?;
        let found = Self::check_version(&tx)?;
        for (i, m) in MIGRATIONS.iter().enumerate().skip(found as usize) {
            tx.execute_batch(m)?;
            tx.execute_batch(&format!("PRAGMA user_version = {}", i + 1))?;
        }
        tx.commit()?;
        Ok(())
    }

    /// A write transaction that takes the write lock at once (waiting up to the
    /// busy timeout). A deferred one that read first would fail at once with
    /// "database is locked" when another program wrote in between.
    fn write(&mut self) -> Result<Transaction<'_>, DbError> {
        Ok(self
            .conn
            .transaction_with_behavior(TransactionBehavior::Immediate)?)
    }

    /// A write transaction (the write lock taken at once).
    pub fn transaction(&mut self) -> Result<Transaction<'_>, DbError> {
        self.write()
    }

    /// Inserts or replaces a tool (with its ISO properties).
    pub fn put_tool(&mut self, t: &ToolRecord) -> Result<(), DbError> {
        t.validate()?;
        let tx = self.write()?;
        put_tool_tx(&tx, t)?;
        tx.commit()?;
        Ok(())
    }

    /// The tool, or [`DbError::UnknownTool`] when the library has no such row.
    pub fn tool(&self, number: u32) -> Result<ToolRecord, DbError> {
        get_tool(&self.conn, number)?.ok_or(DbError::UnknownTool(number))
    }

    /// The tool, or `None` when (and only when) the library has no such row; every
    /// failure to read it is an error.
    pub fn find_tool(&self, number: u32) -> Result<Option<ToolRecord>, DbError> {
        get_tool(&self.conn, number)
    }

    pub fn tools(&self) -> Result<Vec<ToolRecord>, DbError> {
        // One read transaction: the list and its rows from the same snapshot.
        let tx = self.conn.unchecked_transaction()?;
        let numbers: Vec<u32> = {
            let mut st = tx.prepare("SELECT number FROM tools ORDER BY number")?;
            let rows = st.query_map([], |r| r.get(0))?;
            rows.collect::<Result<_, _>>()
                .map_err(|e| damaged_or_sql("tool numbers".into(), e))?
        };
        numbers
            .into_iter()
            .map(|n| get_tool(&tx, n)?.ok_or(DbError::UnknownTool(n)))
            .collect()
    }

    /// Records presetter values for a tool (and takes them as its L and R while it
    /// has not been measured on the machine).
    pub fn record_presetter(&mut self, number: u32, l: f64, r: f64) -> Result<(), DbError> {
        if !(l >= 0.0 && r >= 0.0 && l.is_finite() && r.is_finite()) {
            return Err(DbError::Invalid(
                "presetter L and R must be non-negative numbers".into(),
            ));
        }
        let tx = self.write()?;
        let mut t = get_tool(&tx, number)?.ok_or(DbError::UnknownTool(number))?;
        tx.execute(
            "INSERT INTO presetter (tool, time, l, r) VALUES (?1, ?2, ?3, ?4)",
            params![number, now(), l, r],
        )?;
        if !t.measured {
            t.l = l;
            t.r = r;
            t.dl = 0.0;
            t.dr = 0.0;
            put_tool_tx(&tx, &t)?;
        }
        tx.commit()?;
        Ok(())
    }

    /// Records the insert mounted on a tool (thread mills): its catalogue
    /// designation and the ISO 13399 INSL and TP the PZ comes from; they also
    /// become the tool's INSL and TP properties.
    pub fn add_insert(
        &mut self,
        number: u32,
        designation: &str,
        insl: f64,
        tp: f64,
    ) -> Result<f64, DbError> {
        let pz = crate::thread::pz(insl, tp).map_err(|e| DbError::Invalid(e.to_string()))?;
        let tx = self.write()?;
        let mut t = get_tool(&tx, number)?.ok_or(DbError::UnknownTool(number))?;
        tx.execute(
            "INSERT INTO inserts (tool, designation, insl, tp) VALUES (?1, ?2, ?3, ?4)",
            params![number, designation, insl, tp],
        )?;
        t.iso.insert("INSL".into(), insl.to_string());
        t.iso.insert("TP".into(), tp.to_string());
        put_tool_tx(&tx, &t)?;
        tx.commit()?;
        Ok(pz)
    }

    /// Inserts mounted on a tool, newest last: (designation, INSL, TP).
    pub fn inserts(&self, number: u32) -> Result<Vec<(String, f64, f64)>, DbError> {
        let mut st = self
            .conn
            .prepare("SELECT designation, insl, tp FROM inserts WHERE tool = ?1 ORDER BY id")?;
        let rows = st.query_map([number], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))?;
        rows.collect::<Result<_, _>>()
            .map_err(|e| damaged_or_sql(format!("inserts of tool {number}"), e))
    }

    /// The newest presetter values (L, R), `None` when none were recorded.
    pub fn latest_presetter(&self, number: u32) -> Result<Option<(f64, f64)>, DbError> {
        latest_presetter(&self.conn, number)
    }

    pub fn events(&self, tool: Option<u32>) -> Result<Vec<EventRecord>, DbError> {
        let mut st = self.conn.prepare(
            "SELECT id, time, tool, decision, reason, inputs, outcome FROM events WHERE ?1 IS NULL OR tool = ?1 ORDER BY id",
        )?;
        let mut rows = st.query([tool])?;
        let mut out = Vec::new();
        while let Some(r) = rows.next()? {
            let id: i64 = r.get(0)?;
            let damaged = |e: &dyn std::fmt::Display| DbError::Damaged(format!("event {id}: {e}"));
            let json = |col: usize, name: &str| -> Result<serde_json::Value, DbError> {
                let text: String = r.get(col).map_err(|e| damaged(&e))?;
                serde_json::from_str(&text)
                    .map_err(|e| damaged(&format!("{name} is not JSON ({e})")))
            };
            out.push(EventRecord {
                id,
                time: r.get(1).map_err(|e| damaged(&e))?,
                tool: r.get(2).map_err(|e| damaged(&e))?,
                decision: r.get(3).map_err(|e| damaged(&e))?,
                reason: r.get(4).map_err(|e| damaged(&e))?,
                inputs: json(5, "inputs")?,
                outcome: json(6, "outcome")?,
            });
        }
        Ok(out)
    }

    /// Whether a pallet is locked; a pallet the library has never locked has no row.
    pub fn pallet_locked(&self, id: &str) -> Result<bool, DbError> {
        Ok(self
            .conn
            .query_row("SELECT locked FROM pallets WHERE id = ?1", [id], |r| {
                r.get::<_, bool>(0)
            })
            .optional()
            .map_err(|e| damaged_or_sql(format!("pallet {id}"), e))?
            .unwrap_or(false))
    }

    pub fn measurement_count(&self) -> Result<i64, DbError> {
        Ok(self
            .conn
            .query_row("SELECT count(*) FROM measurements", [], |r| r.get(0))?)
    }

    /// `PRAGMA integrity_check` answer ("ok" when sound).
    pub fn integrity(&self) -> Result<String, DbError> {
        Ok(self
            .conn
            .query_row("PRAGMA integrity_check", [], |r| r.get(0))?)
    }

    /// Tools as JSON (array; ISO properties as a map).
    pub fn export_json(&self) -> Result<String, DbError> {
        serde_json::to_string_pretty(&self.tools()?).map_err(|e| DbError::Invalid(e.to_string()))
    }

    /// Imports tools from JSON (an array of tools); all or nothing.
    pub fn import_json(&mut self, text: &str) -> Result<usize, DbError> {
        let tools: Vec<ToolRecord> = serde_json::from_str(text)
            .map_err(|e| DbError::Invalid(format!("{}:{}: {e}", e.line(), e.column())))?;
        self.import(&tools)
    }

    fn import(&mut self, tools: &[ToolRecord]) -> Result<usize, DbError> {
        for t in tools {
            t.validate()?;
        }
        let tx = self.write()?;
        for t in tools {
            put_tool_tx(&tx, t)?;
        }
        tx.commit()?;
        Ok(tools.len())
    }

    /// Tools as CSV: the fixed columns, then one `iso:SYMBOL` column per property.
    pub fn export_csv(&self) -> Result<String, DbError> {
        let tools = self.tools()?;
        let symbols: std::collections::BTreeSet<String> =
            tools.iter().flat_map(|t| t.iso.keys().cloned()).collect();
        let mut w = csv::Writer::from_writer(Vec::new());
        let mut header: Vec<String> = CSV_COLUMNS.iter().map(|s| s.to_string()).collect();
        header.extend(symbols.iter().map(|s| format!("iso:{s}")));
        w.write_record(&header).map_err(csv_err)?;
        for t in &tools {
            let mut row = vec![
                t.number.to_string(),
                t.name.clone(),
                t.kind.clone(),
                t.l.to_string(),
                t.r.to_string(),
                t.dl.to_string(),
                t.dr.to_string(),
                t.ltol.to_string(),
                t.rtol.to_string(),
                t.lbreak.to_string(),
                t.rbreak.to_string(),
                (t.locked as u8).to_string(),
                t.sister.map(|s| s.to_string()).unwrap_or_default(),
                t.life_min.map(|s| s.to_string()).unwrap_or_default(),
                t.used_min.to_string(),
                (t.measured as u8).to_string(),
            ];
            row.extend(
                symbols
                    .iter()
                    .map(|s| t.iso.get(s).cloned().unwrap_or_default()),
            );
            w.write_record(&row).map_err(csv_err)?;
        }
        String::from_utf8(
            w.into_inner()
                .map_err(|e| DbError::Invalid(e.to_string()))?,
        )
        .map_err(|e| DbError::Invalid(e.to_string()))
    }

    /// Imports tools from CSV (`number` required; other columns optional; `iso:X`
    /// columns become ISO 13399 properties); all or nothing, errors say line and column.
    pub fn import_csv(&mut self, text: &str) -> Result<usize, DbError> {
        let mut r = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .from_reader(text.as_bytes());
        let header = r.headers().map_err(csv_err)?.clone();
        let col = |name: &str| header.iter().position(|h| h.eq_ignore_ascii_case(name));
        let number_col = col("number")
            .ok_or_else(|| DbError::Invalid("1:1: CSV needs a `number` column".into()))?;
        let mut tools = Vec::new();
        for (i, rec) in r.records().enumerate() {
            let rec = rec.map_err(csv_err)?;
            let line = i + 2;
            let field = |name: &str| col(name).and_then(|c| rec.get(c)).filter(|v| !v.is_empty());
            let num = |name: &str| -> Result<Option<f64>, DbError> {
                match field(name) {
                    None => Ok(None),
                    Some(v) => v.parse::<f64>().map(Some).map_err(|_| {
                        DbError::Invalid(format!(
                            "{line}:{}: `{v}` in column {name} is not a number",
                            col(name).unwrap_or(0) + 1
                        ))
                    }),
                }
            };
            let number: u32 = rec.get(number_col).unwrap_or("").parse().map_err(|_| {
                DbError::Invalid(format!(
                    "{line}:{}: tool number `{}` is not a whole number",
                    number_col + 1,
                    rec.get(number_col).unwrap_or("")
                ))
            })?;
            let mut t = ToolRecord::new(number, field("name").unwrap_or(""));
            if let Some(k) = field("kind") {
                t.kind = k.to_string();
            }
            t.l = num("l")?.unwrap_or(0.0);
            t.r = num("r")?.unwrap_or(0.0);
            t.dl = num("dl")?.unwrap_or(0.0);
            t.dr = num("dr")?.unwrap_or(0.0);
            t.ltol = num("ltol")?.unwrap_or(0.0);
            t.rtol = num("rtol")?.unwrap_or(0.0);
            t.lbreak = num("lbreak")?.unwrap_or(0.0);
            t.rbreak = num("rbreak")?.unwrap_or(0.0);
            t.locked = num("locked")?.map(|v| v != 0.0).unwrap_or(false);
            t.sister = num("sister")?.map(|v| v as u32);
            t.life_min = num("life_min")?;
            t.used_min = num("used_min")?.unwrap_or(0.0);
            t.measured = num("measured")?.map(|v| v != 0.0).unwrap_or(false);
            for (h, v) in header.iter().zip(rec.iter()) {
                if let Some(sym) = h.strip_prefix("iso:") {
                    if !v.is_empty() {
                        t.iso.insert(sym.to_string(), v.to_string());
                    }
                }
            }
            t.validate()
                .map_err(|e| DbError::Invalid(format!("{line}:1: {e}")))?;
            tools.push(t);
        }
        self.import(&tools)
    }

    /// A Heidenhain TOOL.T-style table (TNC column names; L-OFFS carries the PZ of
    /// thread mills with insert data).
    pub fn export_tool_t(&self) -> Result<String, DbError> {
        let mut s = String::from("BEGIN TOOL     .T     MM\n");
        s.push_str(&format!(
            "{:<8}{:<33}{:>12}{:>12}{:>10}{:>10}{:>9}{:>9}{:>9}{:>9}{:>4}{:>6}{:>9}{:>9}{:>9}\n",
            "T",
            "NAME",
            "L",
            "R",
            "DL",
            "DR",
            "LTOL",
            "RTOL",
            "LBREAK",
            "RBREAK",
            "TL",
            "RT",
            "TIME1",
            "CUR_TIME",
            "L-OFFS"
        ));
        for t in self.tools()? {
            let pz = match (
                t.iso.get("INSL").and_then(|v| v.parse::<f64>().ok()),
                t.iso.get("TP").and_then(|v| v.parse::<f64>().ok()),
            ) {
                (Some(l), Some(p)) => crate::thread::pz(l, p).ok(),
                _ => None,
            };
            let name: String = t.name.chars().take(32).collect();
            s.push_str(&format!(
                "{:<8}{:<33}{:>+12.4}{:>+12.4}{:>+10.4}{:>+10.4}{:>9.3}{:>9.3}{:>9.3}{:>9.3}{:>4}{:>6}{:>9}{:>9.1}{:>9}\n",
                t.number,
                name,
                t.l,
                t.r,
                t.dl,
                t.dr,
                t.ltol,
                t.rtol,
                t.lbreak,
                t.rbreak,
                if t.locked { "L" } else { "" },
                t.sister.map(|v| v.to_string()).unwrap_or_default(),
                t.life_min.map(|v| format!("{v:.0}")).unwrap_or_default(),
                t.used_min,
                pz.map(|v| format!("{v:.3}")).unwrap_or_default(),
            ));
        }
        s.push_str("[END]\n");
        Ok(s)
    }

    #[cfg(test)]
    pub(crate) fn conn(&mut self) -> &mut Connection {
        &mut self.conn
    }
}

const CSV_COLUMNS: &[&str] = &[
    "number", "name", "kind", "l", "r", "dl", "dr", "ltol", "rtol", "lbreak", "rbreak", "locked",
    "sister", "life_min", "used_min", "measured",
];

fn csv_err(e: csv::Error) -> DbError {
    match e.position() {
        Some(p) => DbError::Invalid(format!("{}:1: {e}", p.line())),
        None => DbError::Invalid(e.to_string()),
    }
}

/// `PRAGMA user_version`: the number of migrations applied.
fn version(conn: &Connection) -> Result<i64, DbError> {
    Ok(conn.query_row("PRAGMA user_version", [], |r| r.get(0))?)
}

/// A value that does not convert (text in a number column, a number out of range)
/// is damage to report as such; anything else stays SQLite's error.
pub(crate) fn damaged_or_sql(what: String, e: rusqlite::Error) -> DbError {
    match e {
        rusqlite::Error::InvalidColumnType(..)
        | rusqlite::Error::FromSqlConversionFailure(..)
        | rusqlite::Error::IntegralValueOutOfRange(..) => DbError::Damaged(format!("{what}: {e}")),
        e => DbError::Sql(e),
    }
}

pub(crate) fn latest_presetter(
    conn: &Connection,
    number: u32,
) -> Result<Option<(f64, f64)>, DbError> {
    conn.query_row(
        "SELECT l, r FROM presetter WHERE tool = ?1 ORDER BY id DESC LIMIT 1",
        [number],
        |r| Ok((r.get(0)?, r.get(1)?)),
    )
    .optional()
    .map_err(|e| damaged_or_sql(format!("presetter values of tool {number}"), e))
}

/// The tool, `None` only when there is no row for it.
pub(crate) fn get_tool(conn: &Connection, number: u32) -> Result<Option<ToolRecord>, DbError> {
    let damaged = |e| damaged_or_sql(format!("tool {number}"), e);
    let t = conn
        .query_row(
            "SELECT number, name, kind, l, r, dl, dr, ltol, rtol, lbreak, rbreak, locked, sister, life_min, used_min, measured
             FROM tools WHERE number = ?1",
            [number],
            |r| {
                Ok(ToolRecord {
                    number: r.get(0)?,
                    name: r.get(1)?,
                    kind: r.get(2)?,
                    l: r.get(3)?,
                    r: r.get(4)?,
                    dl: r.get(5)?,
                    dr: r.get(6)?,
                    ltol: r.get(7)?,
                    rtol: r.get(8)?,
                    lbreak: r.get(9)?,
                    rbreak: r.get(10)?,
                    locked: r.get(11)?,
                    sister: r.get(12)?,
                    life_min: r.get(13)?,
                    used_min: r.get(14)?,
                    measured: r.get(15)?,
                    iso: BTreeMap::new(),
                })
            },
        )
        .optional()
        .map_err(damaged)?;
    let Some(mut t) = t else { return Ok(None) };
    let mut st = conn.prepare_cached("SELECT symbol, value FROM tool_props WHERE tool = ?1")?;
    for kv in st.query_map([number], |r| {
        Ok((r.get::<_, String>(0)?, r.get::<_, String>(1)?))
    })? {
        let (k, v) = kv.map_err(damaged)?;
        t.iso.insert(k, v);
    }
    Ok(Some(t))
}

pub(crate) fn put_tool_tx(tx: &Connection, t: &ToolRecord) -> Result<(), DbError> {
    tx.execute(
        "INSERT INTO tools (number, name, kind, l, r, dl, dr, ltol, rtol, lbreak, rbreak, locked, sister, life_min, used_min, measured)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16)
         ON CONFLICT(number) DO UPDATE SET name=excluded.name, kind=excluded.kind, l=excluded.l, r=excluded.r,
           dl=excluded.dl, dr=excluded.dr, ltol=excluded.ltol, rtol=excluded.rtol, lbreak=excluded.lbreak,
           rbreak=excluded.rbreak, locked=excluded.locked, sister=excluded.sister, life_min=excluded.life_min,
           used_min=excluded.used_min, measured=excluded.measured",
        params![
            t.number, t.name, t.kind, t.l, t.r, t.dl, t.dr, t.ltol, t.rtol, t.lbreak, t.rbreak, t.locked, t.sister, t.life_min,
            t.used_min, t.measured
        ],
    )?;
    tx.execute("DELETE FROM tool_props WHERE tool = ?1", [t.number])?;
    let mut st =
        tx.prepare_cached("INSERT INTO tool_props (tool, symbol, value) VALUES (?1, ?2, ?3)")?;
    for (k, v) in &t.iso {
        st.execute(params![t.number, k, v])?;
    }
    Ok(())
}

pub(crate) fn log_event(
    tx: &Connection,
    tool: Option<u32>,
    decision: &str,
    reason: &str,
    inputs: &serde_json::Value,
    outcome: &serde_json::Value,
) -> Result<i64, DbError> {
    tx.execute(
        "INSERT INTO events (time, tool, decision, reason, inputs, outcome) VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
        params![now(), tool, decision, reason, inputs.to_string(), outcome.to_string()],
    )?;
    Ok(tx.last_insert_rowid())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_csv_and_json_without_loss() {
        let mut db = ToolDb::memory().expect("db");
        let mut t = ToolRecord::new(5, "MTE D13.7 thread mill");
        t.kind = "thread-mill".into();
        t.l = 120.5;
        t.r = 6.9;
        t.rtol = 0.01;
        t.rbreak = 0.05;
        t.sister = Some(6);
        t.life_min = Some(45.0);
        t.iso.insert("INSL".into(), "14.0".into());
        t.iso.insert("TP".into(), "1.0".into());
        t.iso
            .insert("ZZ_VENDOR".into(), "keep me, with a comma".into());
        db.put_tool(&t).expect("put");
        db.put_tool(&ToolRecord::new(6, "sister")).expect("put");
        let csv = db.export_csv().expect("csv");
        let json = db.export_json().expect("json");
        for (k, text) in [("csv", &csv), ("json", &json)] {
            let mut other = ToolDb::memory().expect("db");
            if k == "csv" {
                other.import_csv(text).expect("import csv");
            } else {
                other.import_json(text).expect("import json");
            }
            assert_eq!(
                other.tools().expect("tools"),
                db.tools().expect("tools"),
                "{k}"
            );
        }
        let tt = db.export_tool_t().expect("tool.t");
        assert!(tt.starts_with("BEGIN TOOL") && tt.trim_end().ends_with("[END]"));
        assert!(tt.contains("0.500"), "L-OFFS carries PZ 0.5: {tt}");
    }

    #[test]
    fn bad_imports_change_nothing() {
        let mut db = ToolDb::memory().expect("db");
        db.put_tool(&ToolRecord::new(1, "keep")).expect("put");
        let e = db
            .import_csv("number,name,r\n2,a,3\n3,b,x\n")
            .expect_err("bad number");
        assert!(e.to_string().starts_with("3:3:"), "{e}");
        assert!(db.import_csv("name\nfoo\n").is_err());
        assert!(db.import_json("[{\"number\": 4, \"r\": -1}]").is_err());
        assert!(db.import_json("[{\"numbr\": 4}").is_err());
        assert_eq!(db.tools().expect("tools").len(), 1);
        assert!(matches!(db.tool(9), Err(DbError::UnknownTool(9))));
    }

    #[test]
    fn inserts_carry_the_pz_data() {
        let mut db = ToolDb::memory().expect("db");
        db.put_tool(&ToolRecord::new(5, "thread mill"))
            .expect("put");
        // Paper 002: ISCAR MT LNHU 1403 I1.00 on the MTE D13.7: INSL 14.0, TP 1.0, PZ 0.50.
        let pz = db
            .add_insert(5, "MT LNHU 1403 I1.00 ISO IC908", 14.0, 1.0)
            .expect("insert");
        assert!((pz - 0.5).abs() < 1e-12);
        assert_eq!(
            db.inserts(5).expect("inserts"),
            vec![("MT LNHU 1403 I1.00 ISO IC908".to_string(), 14.0, 1.0)]
        );
        assert_eq!(
            db.tool(5)
                .expect("tool")
                .iso
                .get("INSL")
                .map(String::as_str),
            Some("14")
        );
        assert!(db.add_insert(5, "bad", 14.0, -1.0).is_err());
        assert!(db.add_insert(9, "none", 14.0, 1.0).is_err());
        assert_eq!(db.inserts(5).expect("inserts").len(), 1);
    }

    #[test]
    fn event_log_is_append_only() {
        let mut db = ToolDb::memory().expect("db");
        let c = db.conn();
        log_event(
            c,
            None,
            "test",
            "because",
            &serde_json::json!({}),
            &serde_json::json!({}),
        )
        .expect("log");
        assert!(c.execute("UPDATE events SET reason = 'x'", []).is_err());
        assert!(c.execute("DELETE FROM events", []).is_err());
        assert_eq!(db.events(None).expect("events").len(), 1);
    }

    #[test]
    fn timestamps_are_iso_8601() {
        let t = now();
        assert_eq!(t.len(), 24, "{t}");
        assert!(t.ends_with('Z') && &t[4..5] == "-" && &t[10..11] == "T");
    }
}
