"""limber.sweep's local worker processes: each runs one task at a time, so the sweep always knows
which configuration a process was running when it died or ran out of time.

Not concurrent.futures.ProcessPoolExecutor: when one of its processes dies, every unfinished task
fails with BrokenProcessPool (one SIGKILLed worker made 14 of 16 configurations error rows), a
running task cannot be stopped, and leaving it on Ctrl-C waits for every pending task.

- A worker is a spawned process (not forked: the parent's kernel may hold threads a forked child
  would lack) with a pipe. It imports limber, says it is ready, then takes a task, sends back the
  task function's return value, and takes the next.
- A worker that dies while it runs a task (a signal, the OOM killer, a crash in the scene loader)
  is replaced, and the task runs again in the new one, up to `retries` more times; then its result
  is a Failure('worker_died'). The other workers and their tasks are untouched. Three workers in a
  row that die before they are ready stop the sweep (WorkerStartError): the environment is broken.
- A task still running `deadline` s after it was handed out has its worker killed (and replaced);
  its result is a Failure('timeout').
- Workers die with the sweep's process: PR_SET_PDEATHSIG (Linux) sends a worker SIGKILL when the
  thread that started it ends, even when the whole process was SIGKILLed; an idle worker also leaves
  when its pipe closes. Workers ignore SIGINT: Ctrl-C reaches the whole process group, and the
  sweep, not each worker, decides what stops (it kills them).
"""
import collections
import ctypes
import multiprocessing
import multiprocessing.connection
import os
import signal
import time

STARTS_BEFORE_GIVING_UP = 3  # workers in a row that die before they are ready


class Failure(Exception):
    """A task that gave no result of its own: `status` is 'worker_died' or 'timeout', the message says why."""

    def __init__(self, status, message):
        super().__init__(status, message)  # both in args: it pickles (a worker sends a reference's)
        self.status, self.message = status, message

    def __str__(self):
        return self.message


class WorkerStartError(RuntimeError):
    """Worker processes die before they can take a task (they cannot import limber, say)."""


def _die_with(parent):
    """Asks Linux to SIGKILL this process when its parent ends; exits if it already has."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG = 1 (linux/prctl.h)
    except (OSError, AttributeError):
        pass  # not Linux: an idle worker still sees its pipe close
    if os.getppid() != parent:  # the parent died before prctl
        os._exit(1)


def _serve(connection, parent):
    """A worker's life: ready, then one task at a time until the pipe closes."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _die_with(parent)
    import limber  # noqa: F401 -- a worker that cannot import limber fails here, before any task

    connection.send("ready")
    while True:
        try:
            function, arguments = connection.recv()
        except EOFError:
            return
        try:
            result = function(*arguments)
        except Exception as error:  # the sweep's task functions catch their own; this is a last guard
            result = error
        connection.send(result)


def _how(exitcode):
    if exitcode is not None and exitcode < 0:
        try:
            return f"killed by {signal.Signals(-exitcode).name}"
        except ValueError:
            return f"killed by signal {-exitcode}"
    return f"exit code {exitcode}"


class _Worker:
    def __init__(self, context):
        self.connection, child = context.Pipe()
        self.process = context.Process(target=_serve, args=(child, os.getpid()), daemon=True)
        self.process.start()
        child.close()  # the child holds its own copy: the parent's would keep the pipe open
        self.ready = False
        self.task = None  # (task, handed out at, attempt)

    def stop(self):
        if self.process.is_alive():
            self.process.kill()
        self.process.join()
        self.connection.close()


class Workers:
    """`count` worker processes; `run(tasks)` yields (key, result) as tasks finish.

    tasks: (key, label, function, arguments) with `function` importable by name (a worker unpickles
    it); label names the task in notes. deadline: s a task may run, or None. note: called with a
    message when a worker died and its task runs again. A context manager giving `run`:
    `with Workers(2) as run: for key, result in run(tasks): ...`; leaving it kills every worker.
    """

    def __init__(self, count, *, deadline=None, retries=2, note=None):
        self.context = multiprocessing.get_context("spawn")
        self.count, self.deadline, self.retries, self.note = count, deadline, retries, note
        self.workers = []

    def __enter__(self):
        return self.run

    def __exit__(self, *exception):
        for worker in self.workers:
            worker.stop()
        self.workers = []

    def run(self, tasks):
        pending = collections.deque((task, 0) for task in tasks)
        self.workers = [_Worker(self.context) for _ in range(min(self.count, len(pending)))]
        failed_starts = 0
        while pending or any(w.task for w in self.workers):
            for worker in self.workers:
                if worker.ready and worker.task is None and pending:
                    task, attempt = pending.popleft()
                    worker.task = (task, time.monotonic(), attempt)
                    try:
                        worker.connection.send(task[2:])
                    except OSError:
                        pass  # it just died: _look finds it so, with its task
            self._wait()
            finished = []
            for worker in list(self.workers):
                kind, value = self._look(worker)
                if kind == "ready":
                    worker.ready, failed_starts = True, 0
                elif kind == "result":
                    finished.append((worker.task[0][0], value))
                    worker.task = None
                elif kind in ("died", "timeout"):
                    self._replace(worker)
                    if not worker.ready:
                        failed_starts += 1
                        if failed_starts >= STARTS_BEFORE_GIVING_UP:
                            raise WorkerStartError(f"{failed_starts} worker processes in a row died before they could take a "
                                                   f"configuration (the last: {value}); their messages are above")
                    elif worker.task:  # (an idle worker that died is only replaced)
                        finished += self._after(kind, value, *worker.task, pending)
            yield from finished

    def _after(self, kind, how, task, _started, attempt, pending):
        """What becomes of a task whose worker died or ran out of time: [] when it runs again."""
        (key, label, *_), deadline = task, self.deadline
        if kind == "timeout":
            return [(key, Failure("timeout", f"still running {deadline:g} s after it started (past the grid's timeout): "
                                             "its worker process was killed"))]
        if attempt < self.retries:
            if self.note:
                self.note(f"{label}: its worker process died ({how}); running it again ({attempt + 1} of {self.retries} retries)")
            pending.appendleft((task, attempt + 1))
            return []
        return [(key, Failure("worker_died", f"its worker process died {attempt + 1} times running it (the last: {how})"))]

    def _wait(self):
        """Until a worker has something to say, dies, or the nearest deadline passes."""
        objects = [w.connection for w in self.workers] + [w.process.sentinel for w in self.workers]
        timeout = None
        if self.deadline is not None:
            starts = [w.task[1] for w in self.workers if w.task]
            if starts:
                timeout = max(0.0, min(starts) + self.deadline - time.monotonic())
        multiprocessing.connection.wait(objects, timeout)

    def _look(self, worker):
        """('ready' | 'result', message), ('died', how), ('timeout', None), or (None, None): nothing new."""
        if worker.connection.poll():  # a message first: a worker may have sent its result just before it died
            try:
                message = worker.connection.recv()
            except (EOFError, OSError):
                worker.process.join()
                return "died", _how(worker.process.exitcode)
            return ("result", message) if worker.ready else ("ready", None)
        if not worker.process.is_alive():
            return "died", _how(worker.process.exitcode)
        if self.deadline is not None and worker.task and time.monotonic() - worker.task[1] >= self.deadline:
            return "timeout", None
        return None, None

    def _replace(self, worker):
        worker.stop()
        self.workers[self.workers.index(worker)] = _Worker(self.context)
