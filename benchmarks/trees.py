"""Two source trees of cgamesh side by side, each run in child processes of its own.

Shared by ``compare_trees.py`` (same meshes?) and ``bench_trees.py`` (no slower?), which hold a
tree before a change (``--base REV``) against the tree after it (``--head``, by default the
working tree these benchmarks live in):

- ``open_trees(base, head)``: a revision is checked out with ``git worktree add --detach`` into a
  temporary folder, removed again on exit, error or interrupt (SIGTERM included); a folder is
  taken as it is (a scratch copy of a tree, say); the working tree is used in place.
- ``Tree.environment()``: the environment of a child running that tree's code. ``PYTHONPATH``
  holds the tree's root (its ``cgamesh``) and a folder with a ``cgamesh_cli`` link to the tree's
  ``cli/`` (the command's package, installed under that name). These come before site-packages,
  so they win over an editable install of another tree; ``check_imports`` (called by every
  child) makes sure they did.
- ``run_once``: one child process to its end, with its wall time, CPU time (its rusage) and peak
  resident memory (its own report); ``Worker``: a child that runs jobs sent one by one.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent  # the working tree these benchmarks belong to
HERE = Path(__file__).resolve().parent
DEFAULT_BASE = "f8376ab"  # the tree before the one-mesher refactor
RESULT = "RESULT "  # a child's answer: this prefix, then one line of JSON


class TreeError(SystemExit):
    """A tree that cannot be had (unknown revision, failed checkout, a child importing the
    wrong code): one line, exit status 2."""

    def __init__(self, message: str):
        super().__init__(2)
        self.message = message

    def __str__(self) -> str:
        return self.message


@dataclass(frozen=True)
class Tree:
    """A source tree of cgamesh: ``label`` (base, head), ``name`` (the revision, folder or
    "working tree"), ``commit`` (None for a folder) and ``root`` (the folder holding cgamesh/, cli/)."""

    label: str
    name: str
    commit: str | None
    root: Path
    shim: Path  # the folder holding the cgamesh_cli link

    def environment(self, **extra: str) -> dict[str, str]:
        """os.environ for a child of this tree: its PYTHONPATH alone (no other tree's entries),
        BLAS pinned to one thread unless the caller's environment says otherwise (the meshers'
        matrix products are small; threads spinning on a shared machine count as CPU time)."""
        env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(self.root), str(self.shim)]), **extra)
        for variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
            env.setdefault(variable, "1")
        env.pop("PYTHONHOME", None)
        return env

    def describe(self) -> str:
        commit = f" ({self.commit[:10]})" if self.commit and not self.name.startswith(self.commit[:7]) else ""
        return f"{self.label} = {self.name}{commit} at {self.root}"


def check_imports(root: str | os.PathLike[str]) -> None:
    """In a child: stop unless ``cgamesh`` and ``cgamesh_cli`` are imported from ``root``."""
    import cgamesh
    import cgamesh_cli

    want = Path(root).resolve()
    for module, folder in ((cgamesh, want / "cgamesh"), (cgamesh_cli, want / "cli")):
        got = Path(module.__file__).resolve().parent
        if got != folder:
            raise SystemExit(f"{module.__name__} was imported from {got}, not from {folder}")


def peak_kb() -> int:
    """In a child: its own peak resident memory in KiB (VmHWM, which starts afresh at exec; the
    rusage of a child can include pages of the parent it was forked from)."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except OSError:
        pass
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def answer(result: dict, stream=None) -> None:
    """In a child: send ``result`` to the parent as one RESULT line."""
    stream = stream or sys.stdout
    stream.write(RESULT + json.dumps(result) + "\n")
    stream.flush()


def _git(*args: str, cwd: Path = ROOT) -> str:
    done = subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True)
    if done.returncode != 0:
        message = (done.stderr.strip().splitlines() or ["(no message)"])[-1]
        raise TreeError(f"git {' '.join(args)}: {message}")
    return done.stdout.strip()


def resolve(rev: str) -> str:
    """The commit ``rev`` names, or TreeError naming it."""
    done = subprocess.run(["git", "rev-parse", "--verify", "--quiet", f"{rev}^{{commit}}"], cwd=ROOT,
                          capture_output=True, text=True)
    if done.returncode != 0:
        raise TreeError(f"unknown revision {rev!r} (not a commit of the repository at {ROOT})")
    return done.stdout.strip()


@contextlib.contextmanager
def _terminated_as_interrupt():
    """SIGTERM raises KeyboardInterrupt while inside, so every ``finally`` (worktree removal) runs."""
    def stop(signum, frame):
        raise KeyboardInterrupt(f"signal {signum}")

    try:
        previous = signal.signal(signal.SIGTERM, stop)
    except ValueError:  # not the main thread: leave the signal alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@contextlib.contextmanager
def _tree(label: str, spec: str | None, scratch: Path):
    """The Tree ``spec`` names: None for the working tree, a folder, or a revision (checked out
    into ``scratch``, removed on exit)."""
    shim = scratch / f"{label}-path"
    shim.mkdir()
    if spec is None:
        root, name, commit, checkout = ROOT, "working tree", None, None
    elif Path(spec).is_dir() and (Path(spec) / "cgamesh").is_dir():
        root, name, commit, checkout = Path(spec).resolve(), str(spec), None, None
    else:
        commit = resolve(spec)
        checkout = scratch / f"{label}-tree"
        _git("worktree", "add", "--detach", "--quiet", str(checkout), commit)
        root, name = checkout, spec
    try:
        if not (root / "cgamesh").is_dir() or not (root / "cli").is_dir():
            raise TreeError(f"{spec or root}: no cgamesh/ and cli/ in {root}")
        (shim / "cgamesh_cli").symlink_to(root / "cli", target_is_directory=True)
        yield Tree(label, name, commit, root, shim)
    finally:
        if checkout is not None:
            removed = subprocess.run(["git", "worktree", "remove", "--force", str(checkout)], cwd=ROOT,
                                     capture_output=True, text=True)
            if removed.returncode != 0:
                print(f"could not remove the worktree {checkout}: {removed.stderr.strip()}", file=sys.stderr)


@contextlib.contextmanager
def open_trees(base: str, head: str | None = None):
    """(base Tree, head Tree): ``base`` a revision or folder, ``head`` one too or None for the
    working tree. Checkouts live in one temporary folder, removed on exit, error or interrupt."""
    with _terminated_as_interrupt(), tempfile.TemporaryDirectory(prefix="cgamesh-trees-") as folder:
        scratch = Path(folder)
        with _tree("base", base, scratch) as first, _tree("head", head, scratch) as second:
            yield first, second


@dataclass(frozen=True)
class Run:
    """One child process: wall seconds (as the parent saw it), user and system CPU seconds (its
    rusage), peak resident MiB (its own report, 0 if it gave none) and its RESULT (or None)."""

    wall: float
    user: float
    system: float
    peak_mb: float
    result: dict | None

    @property
    def cpu(self) -> float:
        return self.user + self.system


def run_once(tree: Tree, argv: list[str], cwd: Path | None = None, env: dict | None = None) -> Run:
    """Run ``python argv...`` on ``tree``'s code to its end; a failure is a one-line error
    with the tail of the child's stderr."""
    environment = env or tree.environment()
    start = time.perf_counter()
    with tempfile.TemporaryFile() as errors:  # a file, not a pipe: nothing to drain while it runs
        child = subprocess.Popen([sys.executable, *argv], stdout=subprocess.PIPE, stderr=errors,
                                 env=environment, cwd=cwd or HERE)
        try:
            output = child.stdout.read().decode()
        except BaseException:  # an interrupt: no child left behind
            child.kill()
            child.wait()
            raise
        child.stdout.close()
        _, status, usage = os.wait4(child.pid, 0)
        wall = time.perf_counter() - start
        code = os.waitstatus_to_exitcode(status)
        child.returncode = code
        if code != 0:
            errors.seek(0)
            tail = errors.read().decode(errors="replace").strip()[-2000:]
            raise TreeError(f"{tree.label} child {' '.join(map(str, argv))} exited with status {code}:\n{tail}")
    results = [json.loads(line[len(RESULT):]) for line in output.splitlines() if line.startswith(RESULT)]
    result = results[-1] if results else None
    peak = result.get("peak_kb", 0) / 1024.0 if result else 0.0
    return Run(wall, usage.ru_utime, usage.ru_stime, peak, result)


class Worker:
    """A child of ``tree`` running ``script`` that reads one JSON job a line on stdin and
    answers each with a RESULT line on stdout (anything else it prints goes to stderr)."""

    def __init__(self, tree: Tree, script: Path, *args: str):
        self.tree, self.argv = tree, [sys.executable, str(script), str(tree.root), *args]
        self.log = tempfile.TemporaryFile()
        self.child = None

    def start(self) -> dict:
        """Start the child; its first answer (the worker says where its cgamesh came from)."""
        self.child = subprocess.Popen(self.argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self.log,
                                      env=self.tree.environment(), cwd=HERE, text=True, bufsize=1)
        hello = self._receive()
        if hello is None:
            raise TreeError(f"the {self.tree.label} worker did not start:\n{self.stderr_tail()}")
        return hello

    def send(self, job: dict) -> None:
        if self.child is None or self.child.poll() is not None:
            self.start()
        self.child.stdin.write(json.dumps(job) + "\n")
        self.child.stdin.flush()

    def receive(self) -> dict:
        """The answer to the job sent last; a worker that died answers {"died": stderr tail}
        (and is started afresh for the next job)."""
        result = self._receive()
        if result is None:
            self.child.wait()
            result = {"died": f"worker exited with status {self.child.returncode}: {self.stderr_tail()}"}
            self.child = None
        return result

    def _receive(self) -> dict | None:
        for line in self.child.stdout:
            if line.startswith(RESULT):
                return json.loads(line[len(RESULT):])
        return None

    def stderr_tail(self, size: int = 800) -> str:
        self.log.seek(0)
        text = self.log.read().decode(errors="replace").strip()
        self.log.seek(0, os.SEEK_END)
        return text[-size:]

    def close(self, kill: bool = False) -> None:
        """End the child: after its current job, or at once with ``kill`` (an interrupt)."""
        if self.child is not None and self.child.poll() is None:
            if kill:
                self.child.kill()
            with contextlib.suppress(BrokenPipeError):
                self.child.stdin.close()
            try:
                self.child.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.child.kill()
                self.child.wait()
        self.log.close()


def load_average() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


# bench_scene_batch.py's scene, written by a tree's own benchmark helpers (run in its
# benchmarks/ folder), so that both trees read the file the base tree's benchmark meshes.
_BENCH_SCENE = """
import sys
from pathlib import Path
from bench_scene_reader import flow_style, scene_document
path, kind, surfaces, controls, interpolation = Path(sys.argv[1]), sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
if kind == "ribbon":
    from bench_scene_batch import ribbon_document
    path.write_text(ribbon_document(surfaces, controls))
else:
    text = flow_style(scene_document(surfaces, controls))
    path.write_text(text.replace("    type: circles\\n", f"    type: circles\\n    interpolation: {interpolation}\\n"))
"""


def bench_scene(tree: Tree, path: Path, surfaces: int, controls: int = 4, interpolation: str = "blade",
                kind: str = "tube") -> Path:
    """Write the scene of ``bench_scene_batch.py --surfaces S --controls C --interpolation I
    --kind K`` to ``path``, as ``tree``'s benchmarks write it."""
    run_once(tree, ["-c", _BENCH_SCENE, str(path), kind, str(surfaces), str(controls), interpolation],
             cwd=tree.root / "benchmarks")
    return path


def compile_tree(tree: Tree) -> None:
    """Byte-compile the tree's packages, so no timed run of a fresh checkout pays for it."""
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(tree.root / "cgamesh"), str(tree.root / "cli")],
                   check=True, stdout=subprocess.DEVNULL)


def run_tool(name: str, main) -> None:
    """Run a tool's ``main()`` as a command: exit with its status; a TreeError or an interrupt
    is one line on stderr (exit 2 and 130)."""
    try:
        sys.exit(main())
    except TreeError as error:
        print(f"{name}: error: {error}", file=sys.stderr)
        sys.exit(2)
    except KeyboardInterrupt:
        print(f"{name}: interrupted", file=sys.stderr)
        sys.exit(130)
