"""cgamesh batch: many inputs on a Dask cluster, each checked against the single-file command.

A LocalCluster of 2 worker processes (shared by the module) meshes about 50 inputs of every
kind, to GLB and PLY: jittered copies of the examples, nibabel's real .trk and .tck files, a
small SWC neuron, and malformed scene, SWC and tractography files. Every good output must be
byte-identical to the single-file command's and read back through pygltflib to the same mesh;
every bad input must be reported with its path and reason; a worker killed mid-run must not
stop the run; a rerun skips what is done and redoes what changed.
"""

from __future__ import annotations

import json
import logging
import os
import signal
import subprocess
import time
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

import cgamesh
from cgamesh.batching.discovery import discover, plan_outputs
from cgamesh.batching.manifest import MANIFEST_NAME
from cgamesh.errors import InvalidInputError
from cgamesh.readers.readback import read_gltf
from cgamesh_cli.main import main
from realdata_files import nibabel_file

from dask import distributed  # the test extra installs it: never a skip

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = sorted((ROOT / "examples").glob("*.yaml"))
OPTIONS = {"around": 6, "along": 12, "radius": 0.5}  # each input takes the options it concerns
CLI_OPTIONS = ["--around", "6", "--along", "12"]  # the single-file command's, for a scene file
CENTRELINE_CLI_OPTIONS = ["--around", "6", "--radius", "0.5"]  # and for a centreline file
# a small branched neuron: soma, two dendrites, an axon that forks
SWC = "# a test neuron\n" + "".join(f"{i} {t} {x} {y} {z} {r} {p}\n" for i, t, x, y, z, r, p in (
    (1, 1, 0, 0, 0, 2.0, -1), (2, 3, 3, 1, 0, 0.6, 1), (3, 3, 6, 3, 1, 0.5, 2), (4, 3, 9, 4, 1, 0.4, 3),
    (5, 3, -3, 1, 0, 0.6, 1), (6, 3, -6, 2, -1, 0.5, 5), (7, 2, 0, -4, 0, 0.5, 1), (8, 2, 0, -8, 1, 0.4, 7),
    (9, 2, 2, -11, 1, 0.3, 8), (10, 2, -2, -11, 2, 0.3, 8), (11, 2, -3, -14, 2, 0.25, 10)))
FORMATS = ("glb", "ply")
CONTROL = "cgamesh: 1\nsurfaces:\n  - {name: t, type: circles, curve: linear, %scontrols: [{center: [0,0,0], normal: [0,0,1], radius: %s}, {center: [0,0,%s], normal: [0,0,%s], radius: 1}]}\n"
# name -> (file contents, a fragment of the reason the batch must report)
MALFORMED = {
    "lab1/truncated.yaml": ("cgamesh: 1\nsurfaces: [", "invalid YAML"),
    "lab1/empty.yaml": ("", "got an empty document"),
    "lab1/binary.yaml": (b"\xff\xfe\x00\x01 not text", "must be UTF-8 text"),
    "lab1/unknown_key.yaml": ("cgamesh: 1\ncolour: red\nsurfaces: []\n", "colour is not a known key"),
    "lab2/version.yaml": ("cgamesh: 7\nsurfaces: []\n", "supported format version"),
    "lab2/no_surfaces.yaml": ("cgamesh: 1\nunits: m\n", "surfaces must be given"),
    "lab2/deep/nan_radius.yaml": (CONTROL % ("", ".nan", 1, 1), "radius must be a finite number"),
    "lab2/deep/negative_radius.yaml": (CONTROL % ("", -1, 1, 1), "radius must be > 0"),
    # valid to the loader, impossible to mesh: the failure comes from the meshing stage
    "lab2/deep/opposite.yaml": (CONTROL % ("align: false, ", 1, 0, -1), "has no blade projection"),
    "lab3/cycle.swc": ("1 1 0 0 0 1 -1\n2 3 0 0 5 0.5 3\n3 3 0 5 5 0.5 2\n", "node 2 is its own ancestor"),
    "lab3/truncated.trk": (lambda: nibabel_file("standard.trk").read_bytes()[:2903], "expected a valid .trk file"),
    "lab3/text.tck": ("mrtrix tracks\nnot really\n", "expected a valid .tck file"),
}
PARTIAL = {"complex.trk": "1 segment could not be meshed and were left out"}
REAL_FILES = {"lab3/standard.trk": "standard.trk", "lab3/standard_mrtrix.tck": "standard.tck", "lab3/complex.trk": "complex.trk"}


def jittered(example: Path, seed: int) -> str:
    """The example with every coordinate list in its controls moved by about 1e-2."""
    document = yaml.safe_load(example.read_text())
    rng = np.random.default_rng(seed)

    def move(value):
        if isinstance(value, list) and value and all(isinstance(v, (int, float)) for v in value):
            return [float(v) + float(rng.normal(0.0, 1e-2)) for v in value]
        if isinstance(value, list):
            return [move(v) for v in value]
        if isinstance(value, dict):
            return {k: (v if k in ("normal",) else move(v)) for k, v in value.items()}
        return value

    for surface in document["surfaces"]:
        surface["controls"] = move(surface["controls"])
    return yaml.safe_dump(document, sort_keys=False)


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    """``(folder, good names, bad names, reference folder)``: ~50 inputs under ``folder``, and
    the single-file command's outputs of every good one under the reference folder."""
    folder = tmp_path_factory.mktemp("inputs")
    good = []
    for copy, subfolder in enumerate(("lab1", "lab2/deep")):
        for index, example in enumerate(EXAMPLES):
            name = f"{subfolder}/{example.stem}_{copy}.yaml"
            (folder / name).parent.mkdir(parents=True, exist_ok=True)
            (folder / name).write_text(jittered(example, 100 * copy + index))
            good.append(name)
    for name, source in REAL_FILES.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_bytes(nibabel_file(source).read_bytes())
        good.append(name)
    (folder / "lab3" / "neuron.swc").write_text(SWC)
    good.append("lab3/neuron.swc")
    for name, (contents, _) in MALFORMED.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        contents = contents() if callable(contents) else contents
        (folder / name).write_bytes(contents if isinstance(contents, bytes) else contents.encode())
    (folder / "lab1" / "notes.txt").write_text("not an input: folders are searched by extension")
    (folder / "lab1" / ".hidden.yaml").write_text("hidden files are skipped")
    reference = tmp_path_factory.mktemp("reference")
    for name in good:
        reference_outputs(folder / name, reference / name)
    return folder, good, list(MALFORMED), reference


def reference_outputs(source: Path, target: Path) -> None:
    """The single-file command's GLB and PLY of ``source`` at ``target`` with each extension."""
    target.parent.mkdir(parents=True, exist_ok=True)
    outputs = [a for fmt in FORMATS for a in ("-o", str(target.with_suffix("." + fmt)))]
    options = CLI_OPTIONS if source.suffix == ".yaml" else CENTRELINE_CLI_OPTIONS
    # exit 3: written, with the parts that could not be meshed named (complex.trk has a one-point streamline)
    expected = 3 if source.name in PARTIAL else 0
    assert main([str(source), *outputs, *options, "-q"]) == expected


@pytest.fixture(scope="module")
def client():
    """Two worker processes of one thread each; a task survives one death of its worker."""
    import dask

    with dask.config.set({"distributed.scheduler.allowed-failures": 1, "distributed.scheduler.worker-saturation": 1.0}):
        cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                           dashboard_address=":0", silence_logs=logging.ERROR)
    with cluster, distributed.Client(cluster) as dask_client:
        yield dask_client


def assert_same_as_single_file_command(outdir: Path, reference: Path, name: str) -> None:
    for fmt in FORMATS:
        made, expected = (outdir / name).with_suffix("." + fmt), (reference / name).with_suffix("." + fmt)
        assert made.read_bytes() == expected.read_bytes(), f"{made} differs from the single-file command's output"
    made_meshes, expected_meshes = read_gltf((outdir / name).with_suffix(".glb")), read_gltf((reference / name).with_suffix(".glb"))
    assert len(made_meshes) == len(expected_meshes) > 0
    for made, expected in zip(made_meshes, expected_meshes):
        for attribute in ("positions", "normals", "uvs", "faces"):
            np.testing.assert_array_equal(getattr(made, attribute), getattr(expected, attribute))


def test_fifty_mixed_inputs_on_two_workers_match_the_single_file_command(dataset, client, tmp_path):
    folder, good, bad, reference = dataset
    assert len(good) + len(bad) >= 45
    summary = cgamesh.batch([folder], tmp_path, client=client, formats=list(FORMATS), **OPTIONS)

    assert (summary.done, summary.skipped, summary.failed) == (len(good), 0, len(bad))
    by_name = {r.name: r for r in summary.records}
    assert set(by_name) == set(good) | set(bad)  # notes.txt and .hidden.yaml were not inputs
    for name in good:
        assert by_name[name].status == "done"
        assert by_name[name].reason == PARTIAL.get(Path(name).name, "")
        assert_same_as_single_file_command(tmp_path, reference, name)
        meshes = read_gltf(reference / Path(name).with_suffix(".glb"))
        assert by_name[name].vertices == sum(len(m.positions) for m in meshes)
    for name in bad:
        record = by_name[name]
        assert record.status == "failed"
        assert MALFORMED[name][1] in record.reason, record.reason
        assert name.split("/")[-1] in record.reason  # the reason names the file
        assert not any(Path(o).exists() for o in record.outputs)
    assert {p.name for p in tmp_path.rglob(".*")} == set()  # no temporary file left behind

    manifest = json.loads((tmp_path / MANIFEST_NAME).read_text())["inputs"]
    assert set(manifest) == set(good) | set(bad)
    import hashlib
    for name in good:
        entry = manifest[name]
        assert entry["sha256"] == hashlib.sha256((folder / name).read_bytes()).hexdigest()
        assert entry["options"] == OPTIONS and entry["status"] == "done" and entry["tool"].startswith("cgamesh ")
        assert entry["bytes"] == sum((tmp_path / o).stat().st_size for o in entry["outputs"])
        assert entry["seconds"] > 0


def test_a_worker_killed_mid_run_does_not_stop_the_run(dataset, client, tmp_path):
    folder, good, _, reference = dataset
    inputs = [folder / name for name in good[:24]]
    pids = sorted(client.run(os.getpid).values())
    assert len(pids) == 2
    killed = []

    def kill_one_worker(record):
        if not killed:  # after the first result: both workers are busy with the next inputs
            os.kill(pids[0], signal.SIGKILL)
            killed.append(pids[0])

    summary = cgamesh.batch(inputs, tmp_path, client=client, formats=list(FORMATS), on_record=kill_one_worker, **OPTIONS)

    assert killed
    assert (summary.done, summary.failed) == (len(inputs), 0), [r.reason for r in summary.failures]
    for name in good[:24]:  # from two folders: their common folder is the dataset's
        assert_same_as_single_file_command(tmp_path, reference, name)
    client.wait_for_workers(2, timeout=60)  # the nanny started a new process in place of the killed one
    assert pids[0] not in client.run(os.getpid).values()


def test_a_task_whose_worker_always_dies_is_reported_and_the_others_finish(dataset, client, tmp_path):
    from cgamesh.batching.engine import run_batch
    from cgamesh.batching.job import run_job

    folder, good, _, _ = dataset
    doomed = good[0]

    def job(source, outputs, options):  # pickled by value: it runs in the workers
        if source.endswith(Path(doomed).name):
            os._exit(1)  # the worker process dies, every time
        return run_job(source, outputs, options)

    inputs = [folder / name for name in good[:6]]
    summary = run_batch(inputs, tmp_path, client=client, job=job, **OPTIONS)
    assert (summary.done, summary.failed) == (5, 1)
    (failure,) = summary.failures
    assert failure.input.endswith(Path(doomed).name) and "worker process died" in failure.reason
    client.wait_for_workers(2, timeout=60)


def test_workers_running_another_cgamesh_are_refused(dataset, client, tmp_path, monkeypatch, capsys):
    import cgamesh.batching.engine

    folder, good, _, _ = dataset
    monkeypatch.setattr(cgamesh.batching.engine, "tool_version", lambda: "cgamesh 99.0")
    with pytest.raises(InvalidInputError, match=r"2 of 2 Dask workers do not run cgamesh 99.0 .* has cgamesh "):
        cgamesh.batch(folder / good[0], tmp_path, client=client, **OPTIONS)
    assert not list(tmp_path.rglob("*.glb"))


def test_a_rerun_skips_finished_inputs_and_redoes_a_changed_one(dataset, client, tmp_path):
    folder, good, _, _ = dataset
    work = tmp_path / "inputs"
    for name in good[:5] + ["lab1/truncated.yaml"]:
        (work / name).parent.mkdir(parents=True, exist_ok=True)
        (work / name).write_bytes((folder / name).read_bytes())
    out = tmp_path / "out"
    first = cgamesh.batch(work, out, client=client, **OPTIONS)
    assert (first.done, first.skipped, first.failed) == (5, 0, 1)
    times = {p: p.stat().st_mtime_ns for p in out.rglob("*.glb")}

    again = cgamesh.batch(work, out, client=client, **OPTIONS)
    assert (again.done, again.skipped, again.failed) == (0, 5, 1)  # the failed one is tried again
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*.glb")} == times

    changed = work / good[2]
    changed.write_text(jittered(EXAMPLES[0], 999))
    third = cgamesh.batch(work, out, client=client, **OPTIONS)
    assert (third.done, third.skipped) == (1, 4)
    (redone,) = [r for r in third.records if r.status == "done"]
    assert redone.name == Path(good[2]).name  # named relative to the inputs' common folder, lab1
    reference = tmp_path / "reference" / "changed"
    reference_outputs(changed, reference)
    assert Path(redone.outputs[0]).read_bytes() == reference.with_suffix(".glb").read_bytes()

    (out / Path(good[0]).with_suffix(".glb").name).unlink()  # a missing output is made again
    assert cgamesh.batch(work, out, client=client, **OPTIONS).done == 1
    assert cgamesh.batch(work, out, client=client, around=7, along=12).done == 5  # other options
    assert cgamesh.batch(work, out, client=client, around=7, along=12).done == 0
    forced = cgamesh.batch(work, out, client=client, force=True, around=7, along=12)
    assert (forced.done, forced.skipped, forced.failed) == (5, 0, 1)


def test_the_command_line_exit_codes_and_json(dataset, tmp_path, capsys):
    folder, good, _, reference = dataset
    listing = tmp_path / "inputs.txt"
    listing.write_text("# two inputs\n" + "\n".join(str(folder / name) for name in good[:2]) + "\n\n")
    out = tmp_path / "out"
    assert main(["batch", "--manifest", str(listing), "-o", str(out), "--format", "glb,ply", "--workers", "1",
                 *CLI_OPTIONS, "-q"]) == 0
    for name in good[:2]:
        assert_same_as_single_file_command(out, reference / Path(name).parent, Path(name).name)
    capsys.readouterr()

    bad = folder / "lab1" / "truncated.yaml"
    assert main(["batch", str(folder / good[0]), str(bad), "-o", str(tmp_path / "out2"), "--workers", "1",
                 *CLI_OPTIONS, "--json"]) == 3
    captured = capsys.readouterr()
    report = json.loads(captured.out)
    assert (report["done"], report["failed"]) == (1, 1)
    assert [line for line in captured.err.splitlines() if line.startswith("cgamesh: batch: failed: ")] == [
        f"cgamesh: batch: failed: {r['reason']}" for r in report["inputs"] if r["status"] == "failed"]
    assert str(bad) in captured.err and "invalid YAML" in captured.err

    for wrong in (["--format", "glb,xyz"], ["--tolerance", "0.1", "--around", "8"], ["--retries", "-1"],
                  ["--around", "many"], ["--memory-limit", "lots"], ["--scheduler", "not-an-address"]):
        try:
            status = main(["batch", str(folder / good[0]), "-o", str(tmp_path / "out3"), *wrong])
        except SystemExit as exit_:  # argparse's own refusal
            status = exit_.code
        assert status == 2, wrong
    assert main(["batch", str(tmp_path / "nothing-here" / "*.yaml"), "-o", str(tmp_path / "out3")]) == 2
    assert "no input files found" in capsys.readouterr().err


def test_the_command_runs_on_an_existing_scheduler(dataset, client, tmp_path, monkeypatch, capsys):
    folder, good, _, reference = dataset
    address = client.scheduler.address
    assert main(["batch", str(folder / good[0]), "-o", str(tmp_path / "a"), "--scheduler", address, *CLI_OPTIONS]) == 0
    captured = capsys.readouterr()
    assert "on 2 workers" in captured.out
    assert "cgamesh: batch: dashboard http" in captured.err  # on a cluster, its dashboard's link
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", address)  # Dask's own setting, as `dask worker` users have it
    assert main(["batch", str(folder / good[1]), "-o", str(tmp_path / "b"), *CLI_OPTIONS, "-q"]) == 0
    for out, name in ((tmp_path / "a", good[0]), (tmp_path / "b", good[1])):
        glb = Path(name).with_suffix(".glb")
        assert (out / glb.name).read_bytes() == (reference / glb).read_bytes()
    import dask

    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        assert main(["batch", str(folder / good[0]), "-o", str(tmp_path / "c"), "--scheduler", "tcp://127.0.0.1:1"]) == 2
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:1" in capsys.readouterr().err


def test_a_local_cluster_has_single_threaded_workers_within_the_memory_limit():
    from cgamesh.batching.cluster import open_client

    with open_client(workers=1, memory_limit="300MB", retries=1) as (local, on_cluster):
        workers = local.scheduler_info()["workers"].values()
        assert not on_cluster
        assert [(w["nthreads"], w["memory_limit"]) for w in workers] == [(1, 300_000_000)]


def test_without_dask_the_command_names_the_extra(dataset, tmp_path, monkeypatch, capsys):
    folder, good, _, _ = dataset
    for module in ("dask", "dask.distributed", "distributed"):
        monkeypatch.setitem(sys.modules, module, None)  # `import dask` now raises ImportError
    assert main(["batch", str(folder / good[0]), "-o", str(tmp_path)]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "cgamesh[batch]" in line and "'dask'" in line


def test_importing_cgamesh_and_its_batch_entry_point_does_not_import_dask():
    probe = "import sys, cgamesh; f = cgamesh.batch; assert callable(f); print('dask' in sys.modules)"
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "False"


def test_discovery_files_folders_globs_and_listings(tmp_path):
    for name in ("a/x.yaml", "a/b/y.YML", "a/b/.tmp.yaml", "c/z.yaml", "c/skip.txt"):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text("")
    found = discover([tmp_path / "a", str(tmp_path / "c" / "*.yaml"), tmp_path / "a" / "x.yaml"])
    assert found == [tmp_path / "a/b/y.YML", tmp_path / "a/x.yaml", tmp_path / "c/z.yaml"]
    planned = plan_outputs(found, tmp_path / "out", ["glb", "usdz"])
    assert [p.name for p in planned] == ["a/b/y.YML", "a/x.yaml", "c/z.yaml"]
    assert planned[0].outputs == (tmp_path / "out/a/b/y.glb", tmp_path / "out/a/b/y.usdz")

    listing = tmp_path / "a" / "list.txt"
    listing.write_text("# comment\nx.yaml\n\nb/y.YML\nmissing.yaml\n")
    from_listing = discover([], listing)
    assert [p.name for p in plan_outputs(from_listing, tmp_path / "out", ["glb"])] == ["x.yaml", "b/y.YML", "missing.yaml"]
    assert [p.missing for p in plan_outputs(from_listing, tmp_path / "out", ["glb"])] == [False, False, True]

    (tmp_path / "a" / "x.yml").write_text("")
    with pytest.raises(InvalidInputError, match="would both be written to"):
        plan_outputs(discover([tmp_path / "a"]), tmp_path / "out", ["glb"])
    with pytest.raises(InvalidInputError, match="no input files found"):
        discover([tmp_path / "c" / "*.json"])


@pytest.mark.slow
def test_the_benchmark_runs_at_a_tiny_size(tmp_path):
    result = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_batch.py"), "--inputs", "6",
                             "--trivial", "20", "--workers", "1,2", "--around", "6", "--along", "12"],
                            capture_output=True, text=True, timeout=300, cwd=tmp_path,
                            env={**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))})
    assert result.returncode == 0, result.stderr
    assert "per-task overhead" in result.stdout and "to finish in an hour" in result.stdout


@pytest.mark.slow
def test_a_killed_run_leaves_only_whole_files_and_a_rerun_finishes_it(dataset, tmp_path):
    folder, good, _, reference = dataset
    out = tmp_path / "out"
    command = [sys.executable, "-m", "cgamesh_cli.main", "batch", str(folder), "-o", str(out), "--format", "glb,ply",
               "--workers", "2", *CLI_OPTIONS, "-q"]
    run = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
                           env={**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))})
    try:
        deadline = time.monotonic() + 120
        while len(list(out.rglob("*.ply"))) < 4 and run.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
    finally:
        os.killpg(run.pid, signal.SIGKILL)  # the command and its worker processes, mid-run
        run.wait()
    made = [p for p in out.rglob("*") if p.is_file() and not p.name.startswith(".")]
    assert 4 <= len([p for p in made if p.suffix == ".ply"]) < len(good), "the run was not killed mid-run"
    for path in made:
        if path.name != MANIFEST_NAME:
            assert path.read_bytes() == (reference / path.relative_to(out)).read_bytes()
    if (out / MANIFEST_NAME).exists():
        json.loads((out / MANIFEST_NAME).read_text())  # whole, never torn

    summary = cgamesh.batch(folder, out, formats=list(FORMATS), workers=1, **OPTIONS)
    assert (summary.done + summary.skipped, summary.failed) == (len(good), len(MALFORMED))
    for name in good:
        assert_same_as_single_file_command(out, reference, name)
    assert not list(out.rglob(".*.tmp*"))  # the killed run's temporary files were removed
