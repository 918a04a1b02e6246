"""limber.sweep's output file: a CSV table of whole lines, the identity of the grid that wrote it
beside it, and one sweep at a time.

- `<out>.sweep`, beside the table, holds the grid's identity (the SHA-256 of its canonical JSON,
  and that JSON), and is locked (flock) while a sweep writes the table: a second sweep on the same
  file is refused by name. A table is resumed only by its own grid: one without its `.sweep`
  (written by hand, by an older limber.sweep) or with another grid's is refused, not written over.
- A row is appended as one write(2) of a whole line to a file opened O_APPEND, so a killed sweep
  leaves whole lines only; the file is fsync'd at most once a second and when the sweep ends. A
  write that fails (disk full) is cut back to the last whole line and stops the sweep, naming the file.
- Resuming, every line is checked. A line cut short (no newline at its end), with the wrong number
  of fields, a number that does not parse, options that are not its configuration's, or a second
  row of one configuration is moved to `<out>.damaged` with its line number, a note names it, and
  its configuration runs again. Rows whose status a rerun may change (the sweep's `rerun`
  statuses: its worker died, it ran out of time) are dropped, and run again. The table is then
  rewritten (a new file renamed over it) before anything runs.
- Only regular files are read or written: a FIFO, a device or a folder is refused by name, and
  opened, if at all, so that it cannot block (O_NONBLOCK, then fstat).
"""
import csv
import fcntl
import io
import json
import math
import numbers
import os
import stat
import tempfile
import time

KINDS = [(stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
         (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")]


class OutputError(ValueError):
    """A sweep cannot write its output file: the message names the file and the problem."""


def _kind(mode):
    return None if stat.S_ISREG(mode) else next((name for test, name in KINDS if test(mode)), "not a regular file")


def open_regular(path, flags, error, mode=0o644):
    """A file descriptor of `path`, which must be a regular file; `error` (an exception class) names
    the path and the problem. O_NONBLOCK: opening a FIFO returns at once, and fstat refuses it."""
    try:
        kind = _kind(os.stat(path).st_mode)
    except FileNotFoundError:
        kind = None
    except OSError as problem:
        raise error(f"{path}: cannot read its status: {problem.strerror}") from None
    if kind is None:
        try:
            fd = os.open(path, flags | os.O_NONBLOCK | os.O_CLOEXEC, mode)
        except OSError as problem:
            raise error(f"{path}: cannot open: {problem.strerror}") from None
        kind = _kind(os.fstat(fd).st_mode)
        if kind is None:
            os.set_blocking(fd, True)
            return fd
        os.close(fd)
    raise error(f"{path}: is {kind}, not a regular file")


def read_regular(path, cap, error):
    """The bytes of the regular file `path`, at most `cap` of them (else `error` says so)."""
    fd = open_regular(path, os.O_RDONLY, error)
    try:
        chunks, size = [], 0
        while size <= cap:
            chunk = os.read(fd, 1 << 20)
            if not chunk:
                return b"".join(chunks)
            chunks.append(chunk)
            size += len(chunk)
    except OSError as problem:
        raise error(f"{path}: cannot read: {problem.strerror}") from None
    finally:
        os.close(fd)
    raise error(f"{path}: larger than {cap} bytes")


def text(value):
    """How a row's value is written: a float's repr (nan, inf; it reads back to the same bits), an
    integer's digits, None as nan, anything else as its text on one line (a row is one line)."""
    if value is None:
        return "nan"
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return " ".join(str(value).splitlines())
    return str(int(value)) if isinstance(value, numbers.Integral) else repr(float(value))


def line(values):
    """One CSV line (quoted as pandas and csv quote), newline included."""
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerow([text(v) for v in values])
    return out.getvalue()


def _same(field, expected):
    """Whether a field read back is the configuration's value `expected`."""
    if isinstance(expected, numbers.Real) and not isinstance(expected, bool):
        try:
            return float(field) == float(expected) or (math.isnan(float(field)) and math.isnan(float(expected)))
        except ValueError:
            return False
    return field == text(expected)


class Table:
    """An output file opened for a sweep: `finished` (the CSV text of the rows it keeps, header
    first), `append(row)`, `close()`. Made by open_table."""

    def __init__(self, out, lock, columns, configurations, numeric, note):
        self.out, self.lock, self.columns, self.note = out, lock, columns, note
        self.configurations, self.numeric = configurations, numeric
        self.header = line(columns)
        self.fd, self.synced, self.rows = None, time.monotonic(), 0

    def append(self, row):
        """Appends `row` (a dict of the columns) as one whole line; OutputError when it cannot."""
        data = line(row.get(c) for c in self.columns).encode()
        self._write(data)
        self.rows += 1
        if time.monotonic() - self.synced > 1:
            self._sync()

    def close(self):
        try:
            if self.fd is not None:
                self._sync()
        finally:
            if self.fd is not None:
                os.close(self.fd)
            os.close(self.lock)  # and with it the lock
            self.fd = None

    def _sync(self):
        try:
            os.fsync(self.fd)
        except OSError as problem:
            raise OutputError(f"{self.out}: cannot write: {problem.strerror}") from None
        self.synced = time.monotonic()

    def _write(self, data):
        size = os.fstat(self.fd).st_size
        try:
            written = os.write(self.fd, data)
            if written != len(data):
                raise OSError(0, f"only {written} of the row's {len(data)} bytes were written (is the disk full?)")
        except OSError as problem:
            try:
                os.ftruncate(self.fd, size)  # back to the last whole line
            except OSError:
                pass
            raise OutputError(f"{self.out}: cannot write a row: {problem.strerror}; the rows before it are whole, and a "
                              "sweep resumes from them") from None

    def _problem(self, fields, seen):
        """Why a complete line is not a row of this grid, or None."""
        if len(fields) != len(self.columns):
            return f"{len(fields)} fields, expected {len(self.columns)}"
        values = dict(zip(self.columns, fields))
        try:
            index = int(values["index"])
        except ValueError:
            return f"index: not a whole number: {values['index']!r}"
        if not 0 <= index < len(self.configurations):
            return f"index: {index}, this grid's configurations are 0 to {len(self.configurations) - 1}"
        if index in seen:
            return f"a second row of configuration {index} (the first is line {seen[index]})"
        configuration = self.configurations[index]
        for column in self.columns[1:self.columns.index(self.numeric[0])]:  # the scene and the options
            if not _same(values[column], configuration.get(column)):
                return f"{column}: {values[column]!r}, configuration {index}'s is {text(configuration.get(column))!r}"
        for column in self.numeric:
            try:
                float(values[column])
            except ValueError:
                return f"{column}: not a number: {values[column]!r}"
        return None

    def _read(self, content, rerun):
        """The lines of `content` (the table's text) kept, and [(line number, why, text)] set aside;
        rows whose status is in `rerun` are neither."""
        lines = content.split("\n")
        complete, cut = lines[:-1], lines[-1]
        if not complete:  # the header itself cut short
            if not self.header.startswith(cut):
                raise OutputError(f"{self.out}: its first line is not this grid's columns")
            return [], [(1, "cut short: no newline at its end", cut)]
        if complete[0] + "\n" != self.header:
            raise OutputError(f"{self.out}: its columns are not this sweep's ({complete[0][:200]}); it is not resumed or "
                              "written over")
        kept, aside, seen = [], [], {}
        for number, row_text in enumerate(complete[1:], start=2):
            try:
                fields = next(csv.reader([row_text])) if row_text else []
            except csv.Error as problem:
                aside.append((number, f"not CSV: {problem}", row_text))
                continue
            why = self._problem(fields, seen)
            if why:
                aside.append((number, why, row_text))
                continue
            seen[int(fields[0])] = number
            if fields[self.columns.index("status")] not in rerun:
                kept.append(row_text)
        if cut:
            aside.append((len(lines), "cut short: no newline at its end", cut))
        return kept, aside

    def _open(self, identity, description, rerun):
        """Checks the identity, reads and mends the rows, and opens the table for appending."""
        try:
            content = read_regular(self.out, 1 << 40, OutputError).decode("utf-8", "surrogateescape")
        except OutputError:
            if os.path.exists(self.out):
                raise
            content = ""
        if not content:
            self._write_identity(identity, description)
            kept, aside = [], []
        else:
            self._check_identity(identity)
            kept, aside = self._read(content, rerun)
        if aside:
            self._set_aside(aside)
        if not content or aside or len(kept) + 1 != content.count("\n"):
            self._rewrite(kept)
        self.finished = self.header + "".join(k + "\n" for k in kept)
        self.fd = open_regular(self.out, os.O_WRONLY | os.O_APPEND, OutputError)
        self.rows = len(kept)

    def _check_identity(self, identity):
        side = self.out + ".sweep"
        try:
            held = json.loads(os.pread(self.lock, 1 << 24, 0) or b"{}").get("grid_sha256")
        except (ValueError, AttributeError):
            held = None
        if held is None:
            raise OutputError(f"{self.out}: does not say which grid it is a table of (no grid in {side}: a table written by "
                              "hand or by an older limber.sweep); it is not resumed or written over")
        if held != identity:
            raise OutputError(f"{self.out}: holds another grid's table ({side}: grid {held[:12]}, this grid {identity[:12]}); "
                              "it is not resumed or written over")

    def _write_identity(self, identity, description):
        data = (json.dumps({"grid_sha256": identity, "grid": description}, default=str) + "\n").encode()
        try:
            os.ftruncate(self.lock, 0)
            if os.pwrite(self.lock, data, 0) != len(data):
                raise OSError(0, "the disk took only part of it (is it full?)")
            os.fsync(self.lock)
        except OSError as problem:
            raise OutputError(f"{self.out}.sweep: cannot write: {problem.strerror}") from None

    def _set_aside(self, aside):
        damaged = self.out + ".damaged"
        fd = open_regular(damaged, os.O_WRONLY | os.O_APPEND | os.O_CREAT, OutputError)
        try:
            for number, why, content in aside:
                os.write(fd, f"# {self.out} line {number}: {why}\n{content}\n".encode("utf-8", "surrogateescape"))
            os.fsync(fd)
        finally:
            os.close(fd)
        for number, why, _ in aside:
            if self.note:
                self.note(f"{self.out} line {number}: {why}; moved to {damaged}, and its configuration runs again")

    def _rewrite(self, kept):
        """The table as the header and `kept`, renamed over the old one (whole or not at all; over
        the file a symbolic link names, not over the link)."""
        target = os.path.realpath(self.out)
        fd, temporary = tempfile.mkstemp(dir=os.path.dirname(target), prefix=os.path.basename(target) + ".", suffix=".tmp")
        try:
            try:
                os.fchmod(fd, stat.S_IMODE(os.stat(target).st_mode))
            except FileNotFoundError:
                os.fchmod(fd, 0o666 & ~_umask())
            data = (self.header + "".join(k + "\n" for k in kept)).encode("utf-8", "surrogateescape")
            if os.write(fd, data) != len(data):
                raise OSError(0, "the disk took only part of it (is it full?)")
            os.fsync(fd)
        except OSError as problem:
            os.close(fd)
            os.unlink(temporary)
            raise OutputError(f"{self.out}: cannot write: {problem.strerror}") from None
        os.close(fd)
        os.replace(temporary, target)


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


def open_table(out, columns, configurations, numeric, identity, description, *, rerun=(), note=None):
    """The output file `out` opened for a sweep of the grid `identity` (a hash of `description`, a
    JSON-able dict), locked until Table.close. columns: the table's; configurations: the grid's
    (dicts of index, scene and options), to check each row read against; numeric: the columns
    that must hold numbers; rerun: statuses whose rows run again. note: called with a message for
    each line set aside. Raises OutputError naming the file."""
    out = os.fspath(out)
    if not os.path.isdir(os.path.dirname(os.path.abspath(out))):
        raise OutputError(f"{out}: its folder does not exist")
    for path in (out, out + ".sweep"):
        try:
            kind = _kind(os.stat(path).st_mode)
        except OSError:
            kind = None
        if kind:
            raise OutputError(f"{path}: is {kind}, not a regular file")
    side = out + ".sweep"
    created = not os.path.exists(side)
    lock = open_regular(side, os.O_RDWR | os.O_CREAT, OutputError)
    try:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            created = False
            raise OutputError(f"{out}: another sweep is writing it ({side} is locked); wait for it to end, or choose "
                              "another output file") from None
        table = Table(out, lock, columns, configurations, numeric, note)
        table._open(identity, description, rerun)
        return table
    except BaseException:
        if created:
            os.unlink(side)
        os.close(lock)
        raise
