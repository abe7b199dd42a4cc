"""Every OpenCL kernel under the Oclgrind simulator (slow lane; docs/design.md#kernels-under-a-simulator).

Each case of ``tests/oclgrind_cases.py`` runs in a child process under ``oclgrind``, which
reports every invalid memory access and data race of every work-item on stderr; the case
itself compares the kernels' results with the float64 references and reads poison from
every buffer it did not fill. A case passes when it exits 0 and leaves stderr empty.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow
needs_oclgrind = pytest.mark.skipif(shutil.which("oclgrind") is None,
                                    reason="Oclgrind is not installed (`apt-get install oclgrind`; .ci/run installs it)")

SCRIPT = Path(__file__).with_name("oclgrind_cases.py")
#: Oclgrind's checks in every lane, on top of its memory checks (always on): data races, those
#: where the work-items write the same value too.
RACES = ("--data-races", "--uniform-writes")
#: Unoptimised, so that every access the source makes is made; the Random123 functions not
#: forced inline, which Oclgrind 21.10 cannot run unoptimised (an unknown intrinsic).
UNOPTIMISED = ("--build-options", "-cl-opt-disable -DR123_FORCE_INLINE(decl)=decl")
#: The lanes: the kernels as a device compiles them; unoptimised; and unoptimised with Oclgrind's
#: check of uninitialised values, which Oclgrind 21.10 gets right only on the cases it runs.
LANES = {"optimised": RACES, "unoptimised": UNOPTIMISED + RACES,
         "uninitialised": UNOPTIMISED + RACES + ("--uninitialized",)}
ML = ["init", "exact", "pruned", "decide", "ml-run", "ml-pruned-run"]
SEARCH = ["match", "gather", "coherence", "search-runs", "tensor"]
#: (lane, case, the case's options): every case in the first two lanes, and as a GPU would launch
#: them, the cases whose launch shapes depend on the device's type.
RUNS = ([(lane, case, ()) for lane in ("optimised", "unoptimised") for case in ML + SEARCH]
        + [("optimised", case, ("--gpu-shaped",)) for case in ("pruned", "decide", "match")]
        + [("uninitialised", case, ()) for case in ("init", "match")])
#: The first line of each kind of Oclgrind's messages (to count and quote them; a case fails on any stderr).
HEADERS = re.compile(r"^(Invalid |Uninitiali[sz]ed |Read-write |Write-write |Write-read |Work-group |Work-item |"
                     r"Controlflow |Unaligned |Oclgrind|OCLGRIND)", re.M)


def diagnostics(stderr: str) -> list[str]:
    """Oclgrind's messages in *stderr*, each as its lines up to the next blank one."""
    found = []
    for m in HEADERS.finditer(stderr):
        end = stderr.find("\n\n", m.start())
        found.append(stderr[m.start(): None if end < 0 else end].strip())
    return found


def run_case(tmp_path: Path, lane: str, case: str, *options: str) -> subprocess.CompletedProcess:
    """``oclgrind <lane's flags> python tests/oclgrind_cases.py CASE``, with a fresh clsolid cache
    and pyopencl's binary cache off (its cache queries make Oclgrind's API check complain)."""
    path = [str(SCRIPT.parents[1])] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
    env = {**os.environ, "PYOPENCL_NO_CACHE": "1", "CLSOLID_CACHE_DIR": str(tmp_path / "cache"),
           "PYTHONPATH": os.pathsep.join(path)}  # this checkout's clsolid
    return subprocess.run(["oclgrind", *LANES[lane], sys.executable, str(SCRIPT), case, *options],
                          capture_output=True, text=True, env=env, timeout=600)


@needs_oclgrind
@pytest.mark.parametrize("lane, case, options", RUNS, ids=["-".join((lane, case, *o)) for lane, case, o in RUNS])
def test_kernels_agree_with_the_references_and_oclgrind_reports_nothing(tmp_path, lane, case, options):
    run = run_case(tmp_path, lane, case, *options)
    assert run.returncode == 0, f"{case} failed:\n{run.stdout}\n{run.stderr[-4000:]}"
    # nothing at all on stderr: Oclgrind's messages whatever their kind, and Python's warnings
    found = diagnostics(run.stderr)
    assert not run.stderr.strip(), (f"Oclgrind reported {len(found)} problem(s) in {case}; the first:\n"
                                    + "\n\n".join(found[:3]) if found else run.stderr[-4000:])


@needs_oclgrind
@pytest.mark.parametrize("lane", ["optimised", "uninitialised"])
def test_every_fault_of_the_canary_is_reported(tmp_path, lane):
    """The harness can fail: a read past a buffer's end (line 7), an index no one wrote (line 8,
    poisoned: far out of range), a race between two work-items (lines 6 and 9) and, in the
    lane with Oclgrind's check, an uninitialised private value (line 10, written on line 9)."""
    run = run_case(tmp_path, lane, "canary")
    assert run.returncode == 0, run.stderr[-4000:]  # the case itself checks that the float poison arrived
    found = diagnostics(run.stderr)

    def lines(kind: str) -> set[int]:
        return {int(n) for d in found if d.startswith(kind) for n in re.findall(r"At line (\d+) ", d)}

    assert {7, 8} <= lines("Invalid read")
    assert {6, 9} <= lines("Read-write data race")
    assert (9 in lines("Uninitialized value")) == (lane == "uninitialised")


def test_diagnostics_are_told_from_the_programs_own_output():
    stderr = ("a warning of Python's\n\nInvalid read of size 4 at global memory address 0x10\n\tKernel: k\n"
              "\tAt line 3 (column 1) of input.cl:\n\nRead-write data race at local memory address 0x0\n"
              "\tKernel: k\n\nOclgrind: 1000 errors generated - suppressing further errors\n")
    found = diagnostics(stderr)
    assert [d.splitlines()[0] for d in found] == ["Invalid read of size 4 at global memory address 0x10",
                                                 "Read-write data race at local memory address 0x0",
                                                 "Oclgrind: 1000 errors generated - suppressing further errors"]
    assert found[0].endswith("of input.cl:") and not diagnostics("a warning of Python's\n")
