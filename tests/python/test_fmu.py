"""The efsi FMUs (FMI 2.0 and FMI 3.0 Co-Simulation) in fmpy and in Ecos.

`cargo xtask test` builds them first (`cargo xtask fmu …`) into `$EFSI_FMU_DIR` (the sphere
impact, the oscillating Couette flow, the disk in a cavity, the 3-D drop, the 3-D elastic
sphere); the `efsi` binary is `$EFSI_BIN`.
The sphere runs here mostly on a coarse grid (14 x 28 cells, 6 cells per radius) with the
sphere released 6 mm above the substrate, so that it hits within 5 ms; communication steps are
powers of two (2^-10 s), so that the times fmpy computes and efsi's output times are the same
doubles and results compare bit for bit.
"""

import csv
import ctypes
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from ctypes import byref

from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, printLogMessage
from fmpy.logging import addLoggerProxy
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

REPO = Path(__file__).resolve().parents[2]
EFSI = os.environ.get("EFSI_BIN", str(REPO / "target/debug/efsi"))
FMU_DIR = Path(os.environ.get("EFSI_FMU_DIR", str(REPO / "target/fmu")))
FMU2 = str(FMU_DIR / "sphere_impact.fmu")
FMU3 = str(FMU_DIR / "sphere_impact_fmi3.fmu")
FMUS = {"fmi2": FMU2, "fmi3": FMU3}

H = 2.0**-10  # communication step (s), exact in binary
SMALL = {"grid.nr": 14, "grid.nz": 28, "solid.shape.center[1]": 0.025}
OUTPUTS = ["solid_y", "solid_v", "contact_force", "contact_radius", "kinetic_energy",
           "elastic_energy", "steps"]


@pytest.fixture(autouse=True)
def fmpy_logger_proxy():
    """fmpy formats FMI 2.0 messages (a variadic callback) in a native proxy that remembers only
    the last Python logger registered (`fmpy.logging.addLoggerProxy`): once a test's own logger
    is garbage-collected, the next message to fmpy's default callbacks jumps to freed memory.
    After each test, point the proxy at a logger that lives as long as the module."""
    yield
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(printLogMessage)
    addLoggerProxy(byref(callbacks))
    KEPT_CALLBACKS.append(callbacks)


KEPT_CALLBACKS = []


@pytest.fixture(scope="module")
def unzipped():
    """Each FMU extracted once (simulate_fmu and the slaves accept the folder)."""
    dirs = {k: extract(p) for k, p in FMUS.items()}
    yield dirs
    import shutil

    for d in dirs.values():
        shutil.rmtree(d, ignore_errors=True)


def simulate(path, stop, **kw):
    start_values = dict(SMALL)
    start_values.update(kw.pop("start_values", {}))
    return simulate_fmu(path, stop_time=stop, output_interval=H, start_values=start_values,
                        output=OUTPUTS, **kw)


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_fmpy_validate_finds_no_problem(version):
    assert validate_fmu(FMUS[version]) == []


def scene(stop, probe_every):
    """The scene the FMU runs with SMALL, for `efsi run`: the FMU's scene file with the same
    overrides, its probes at the communication points."""
    text = (REPO / "fmu" / "sphere_impact.ron").read_text()
    for old, new in [("grid: (nr: 23, nz: 47)", "grid: (nr: 14, nz: 28)"),
                     ("center: (0.0, 0.0573)", "center: (0.0, 0.025)"),
                     ("end: 0.07,", f"end: {stop!r},"),
                     ("probe_every: 0.001,", f"probe_every: {probe_every!r},")]:
        assert old in text, old
        text = text.replace(old, new)
    return text


def efsi_run(tmp_path, text):
    path = tmp_path / "scene.ron"
    path.write_text(text)
    out = tmp_path / "out"
    # The laws the FMU ships are the release builds (`cargo xtask fmu`): use the same ones.
    env = dict(os.environ, EFSI_LAW_PATH=str(REPO / "target/fmu-release"))
    subprocess.run([EFSI, "run", str(path), "--out", str(out), "-q"], check=True, env=env)
    with open(out / "probes.csv") as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_outputs_equal_efsi_run_of_the_same_scene(version, unzipped, tmp_path):
    stop = 12 * H  # through the impact (contact from ≈ 5 ms)
    r = simulate(unzipped[version], stop)
    p = efsi_run(tmp_path, scene(stop, H))
    assert np.array_equal(r["time"], p["t"])
    for name in OUTPUTS[:-1]:
        # The same solver, the same steps, the same probes: bit for bit.
        assert np.array_equal(r[name], p[name]), name
    assert r["contact_force"].max() > 0.1  # the run does reach the impact (N per radian)
    assert np.all(np.diff(r["steps"]) > 0)


def constant_input(stop, a):
    return np.array([(0.0, a), (stop, a)], dtype=[("time", np.float64), ("base_acceleration", np.float64)])


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_base_acceleration_acts_as_stronger_gravity(version, unzipped):
    """A table accelerating upwards at a: the body force is g − a, i.e. |g| + a."""
    stop, a = 6 * H, 5.0  # free fall: still above the substrate
    start = {"solid.shape.center[1]": 0.0573}
    shaken = simulate(unzipped[version], stop, input=constant_input(stop, a), start_values=start)
    heavier = simulate(unzipped[version], stop, start_values={**start, "gravity.1": -9.81 - a})
    still = simulate(unzipped[version], stop, start_values=start)
    for name in OUTPUTS:
        assert np.array_equal(shaken[name], heavier[name]), name
    # And it does act: the sphere falls ½ a t² further (less the small buoyancy and drag).
    dz = still["solid_y"] - shaken["solid_y"]
    t = shaken["time"]
    assert dz[-1] == pytest.approx(0.5 * a * t[-1] ** 2, rel=0.05)


def slave(version, unzipped, name="sphere", **params):
    md = read_model_description(unzipped[version])
    cls = FMU2Slave if version == "fmi2" else FMU3Slave
    fmu = cls(guid=md.guid, unzipDirectory=unzipped[version],
              modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu.instantiate()
    if version == "fmi2":
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
    else:
        fmu.enterInitializationMode(startTime=0.0)
    for k, v in dict(SMALL, **params).items():
        if isinstance(v, int):
            (fmu.setInteger if version == "fmi2" else fmu.setInt32)([vr[k]], [v])
        else:
            (fmu.setReal if version == "fmi2" else fmu.setFloat64)([vr[k]], [v])
    fmu.exitInitializationMode()
    return fmu, vr


def read(version, fmu, vr):
    real = fmu.getReal if version == "fmi2" else fmu.getFloat64
    count = fmu.getInteger if version == "fmi2" else fmu.getInt64
    return real([vr[n] for n in OUTPUTS[:-1]]) + count([vr["steps"]])


def advance(version, fmu, vr, t, n, h=H, a=None):
    rows = []
    for k in range(n):
        if a is not None:
            (fmu.setReal if version == "fmi2" else fmu.setFloat64)([vr["base_acceleration"]], [a(k)])
        fmu.doStep(t, h)
        t += h
        rows.append(read(version, fmu, vr))
    return t, rows


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_save_state_step_restore_replay_is_bitwise(version, unzipped):
    fmu, vr = slave(version, unzipped)
    shake = lambda k: 3.0 * math.sin(k)  # noqa: E731  (the input is part of the state)
    t, _ = advance(version, fmu, vr, 0.0, 4, a=shake)
    state = fmu.getFMUState()
    t1, first = advance(version, fmu, vr, t, 6, a=lambda k: shake(k + 4))
    fmu.setFMUState(state)
    _, again = advance(version, fmu, vr, t, 6, a=lambda k: shake(k + 4))
    assert again == first
    # Through the serialised form (efsi's checkpoint format) too.
    blob = fmu.serializeFMUState(state)
    restored = fmu.deserializeFMUState(blob)
    fmu.setFMUState(restored)
    _, once_more = advance(version, fmu, vr, t, 6, a=lambda k: shake(k + 4))
    assert once_more == first
    fmu.freeFMUState(state)
    fmu.freeFMUState(restored)
    assert len(blob) > 100_000  # the fields of a 14 x 28 grid with their ghosts
    fmu.terminate()
    fmu.freeInstance()


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_do_step_lands_on_any_communication_point(version, unzipped):
    fmu, vr = slave(version, unzipped)
    real = fmu.getReal if version == "fmi2" else fmu.getFloat64
    t = 0.0
    for h in [0.0007, 1e-5, 0.00123, 0.0031]:
        fmu.doStep(t, h)
        t += h
        assert real([vr["time"]])[0] == t
    fmu.terminate()
    fmu.freeInstance()


# A value outside the variable's declared range is refused when it is set (FMI 3.0: Discard,
# nothing changes; FMI 2.0, which has no Discard for setters: Error); the rest when
# initialisation ends, against the scene and the law.
BAD = [("solid.shape.radius", -0.01, "Set", "solid.shape.radius"), ("grid.nr", 0, "Set", "grid.nr"),
       ("solid.law.name", "no_such_law", "ExitInitializationMode", "solid.law.name"),
       ("grid.nz", 8, "ExitInitializationMode", "refine the grid")]


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
@pytest.mark.parametrize("name,value,where,needle", BAD)
def test_bad_parameter_is_refused_and_named(version, name, value, where, needle, unzipped):
    messages = []
    if version == "fmi2":
        def logger(env, instance, status, category, message):
            messages.append(message.decode())
    else:
        def logger(env, status, category, message):
            messages.append(message.decode())
    with pytest.raises(FMICallException) as e:
        simulate(unzipped[version], 4 * H, start_values={name: value}, logger=logger)
    assert where in e.value.function
    if where == "Set":
        assert e.value.status == (3 if version == "fmi2" else 2)
    assert any(needle in m for m in messages), messages
    # The process survives and the FMU still works.
    assert simulate(unzipped[version], H)["steps"][-1] > 0


def test_two_instances_in_one_process_are_independent(unzipped):
    a, vra = slave("fmi2", unzipped, name="a")
    b, vrb = slave("fmi2", unzipped, name="b", **{"solid.velocity[1]": -0.8,
                                                  "solid.law.parameters.G": 0.5e6})
    ta = tb = 0.0
    rows_a, rows_b = [], []
    for _ in range(8):  # interleaved
        ta, ra = advance("fmi2", a, vra, ta, 1)
        tb, rb = advance("fmi2", b, vrb, tb, 1)
        rows_a += ra
        rows_b += rb
    for f in (a, b):
        f.terminate()
        f.freeInstance()
    alone_a = simulate(unzipped["fmi2"], 8 * H)
    alone_b = simulate(unzipped["fmi2"], 8 * H,
                       start_values={"solid.velocity[1]": -0.8, "solid.law.parameters.G": 0.5e6})
    for k, name in enumerate(OUTPUTS):
        assert [r[k] for r in rows_a] == list(alone_a[name][1:]), name
        assert [r[k] for r in rows_b] == list(alone_b[name][1:]), name
    assert rows_a != rows_b


def readme_example():
    """The co-simulation example of the FMU page (docs/fmu.md), as code."""
    text = (REPO / "docs" / "fmu.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    block = next(b for b in blocks if "def cosimulate" in b)
    namespace = {}
    exec(compile(block, "docs/fmu.md", "exec"), namespace)
    return namespace["cosimulate"]


def test_readme_cosimulation_with_a_spring_damper_substrate(unzipped):
    cosimulate = readme_example()
    stop, h = 16 * H, H / 2
    soft = cosimulate(unzipped["fmi2"], stop_time=stop, step=h, **SMALL)
    # A substrate too heavy to move is the fixed substrate of a plain run, bit for bit.
    rigid = cosimulate(unzipped["fmi2"], stop_time=stop, step=h, mass=1e300, **SMALL)
    plain = simulate_fmu(unzipped["fmi2"], stop_time=stop, output_interval=h,
                         start_values=SMALL, output=["solid_y", "contact_force"])
    assert np.array_equal(rigid["height"], plain["solid_y"][1:])
    assert np.abs(rigid["x"]).max() < 1e-250
    # The impact pushes the substrate down (by ≈ 4 mm); the compliant substrate softens the
    # impact (peak force ≈ 14.4 N against 18.0 N, less compression) and takes energy from the
    # rebound.
    assert soft["x"].min() < -2e-3
    assert soft["force"].max() < 0.9 * rigid["force"].max()
    assert soft["height"].min() > rigid["height"].min() + 2e-4
    assert soft["height"][-1] < rigid["height"][-1] - 5e-4
    assert np.all(np.isfinite(soft["height"]))


# --- Misuse and failure, as an importer meets them (issue 18) ---------------------------------


def real_get(version, fmu):
    return fmu.getReal if version == "fmi2" else fmu.getFloat64


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_a_refused_step_keeps_the_instance_at_its_start(version, unzipped):
    """A doStep over the work bound returns Discard with nothing changed: FMI 3.0 steps on from
    there; FMI 2.0 (stepFailed) goes on after an FMU state is set."""
    fmu, vr = slave(version, unzipped, max_solver_steps_per_step=5)
    t, _ = advance(version, fmu, vr, 0.0, 2)
    state = fmu.getFMUState()
    before = read(version, fmu, vr)
    with pytest.raises(FMICallException) as e:
        fmu.doStep(t, 0.02)
    assert e.value.status == 2  # discard
    assert read(version, fmu, vr) == before
    assert real_get(version, fmu)([vr["time"]])[0] == t
    if version == "fmi2":
        with pytest.raises(FMICallException):  # not in stepFailed
            fmu.doStep(t, H)
        fmu.setFMUState(state)
    t2, rows = advance(version, fmu, vr, t, 2)
    assert rows[-1][-1] > before[-1]
    fmu.freeFMUState(state)
    fmu.terminate()
    fmu.freeInstance()


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_serialised_state_sets_into_another_extraction_before_initialisation(version, tmp_path):
    """Every importer extracts to a fresh folder: a state serialised by one extraction sets into
    an instance of another, in Instantiated mode, and the run continues bit for bit."""
    first, second = extract(FMUS[version], tmp_path / "a"), extract(FMUS[version], tmp_path / "b")
    a, vra = slave(version, {version: first}, name="a")
    t, _ = advance(version, a, vra, 0.0, 3, a=lambda k: 2.0 * k)
    blob = a.serializeFMUState(a.getFMUState())
    assert str(first).encode() not in bytes(blob)
    _, want = advance(version, a, vra, t, 5)
    md = read_model_description(second)
    cls = FMU2Slave if version == "fmi2" else FMU3Slave
    b = cls(guid=md.guid, unzipDirectory=second, modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName="b")
    b.instantiate()
    b.setFMUState(b.deserializeFMUState(blob))  # default parameters until now: the state brings its own
    _, got = advance(version, b, vra, t, 5)
    assert got == want
    for f in (a, b):
        f.terminate()
        f.freeInstance()


CHILD = r'''
import ctypes, sys
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave, fmi2FMUstate
from fmpy.fmi3 import FMU3Slave, fmi3FMUState

version, path = sys.argv[1], sys.argv[2]
md = read_model_description(path)
vr = {v.name: v.valueReference for v in md.modelVariables}
cls = FMU2Slave if version == "fmi2" else FMU3Slave
messages = []
if version == "fmi2":
    def logger(env, instance, status, category, message):
        messages.append(message.decode())
else:
    def logger(env, status, category, message):
        messages.append(message.decode())
fmu = cls(guid=md.guid, unzipDirectory=path, modelIdentifier=md.coSimulation.modelIdentifier,
          instanceName="child")
if version == "fmi2":
    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
    from fmpy.logging import addLoggerProxy
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(logger)
    addLoggerProxy(ctypes.byref(callbacks))
    fmu.instantiate(callbacks=callbacks)
else:
    fmu.instantiate(logMessage=logger)
for name in ["grid.nr", "grid.nz"]:
    (fmu.setInteger if version == "fmi2" else fmu.setInt32)([vr[name]], [14 if name == "grid.nr" else 28])
if version == "fmi2":
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
else:
    fmu.enterInitializationMode(startTime=0.0)
fmu.exitInitializationMode()
fmu.doStep(0.0, 2.0**-10)
Free = getattr(fmu, "fmi2FreeFMUstate" if version == "fmi2" else "fmi3FreeFMUState")
State = fmi2FMUstate if version == "fmi2" else fmi3FMUState


def status(call):
    try:
        call()
        return 0
    except FMICallException as e:
        return e.status


state = fmu.getFMUState()
# The state handle passed by value where its address is meant (seen in the wild).
print("by-value", status(lambda: Free(fmu.component, ctypes.cast(state, ctypes.POINTER(State)))))
print("message", messages[-1])
fmu.setFMUState(state)
# A pointer to something that is not a state.
junk = State(0xdeadbeef)
print("foreign", status(lambda: Free(fmu.component, ctypes.byref(junk))))
fmu.setFMUState(state)
# Freed twice through a copy of the handle.
copy = State(state.value)
fmu.freeFMUState(state)
print("twice", status(lambda: Free(fmu.component, ctypes.byref(copy))))
# An instance freed twice, then used.
component = fmu.component
FreeInstance = getattr(fmu, "fmi2FreeInstance" if version == "fmi2" else "fmi3FreeInstance")
FreeInstance(component)
FreeInstance(component)
DoStep = getattr(fmu, "fmi2DoStep" if version == "fmi2" else "fmi3DoStep")
if version == "fmi2":
    print("after-free", status(lambda: DoStep(component, 0.0, 1e-3, 1)))
else:
    b = ctypes.c_bool()
    d = ctypes.c_double()
    print("after-free", status(lambda: DoStep(component, 0.0, 1e-3, True, ctypes.byref(b),
                                              ctypes.byref(b), ctypes.byref(b), ctypes.byref(d))))
print("alive")
'''


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_importer_mistakes_are_errors_not_crashes(version, unzipped):
    """The mistakes that used to crash the importer — a state passed by value, a foreign pointer,
    a state freed twice, an instance freed twice and used afterwards — each return Error and the
    process lives on. Run in a child process, so a crash fails this test instead of pytest."""
    r = subprocess.run([sys.executable, "-c", CHILD, version, str(unzipped[version])],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    out = dict(line.split(" ", 1) for line in r.stdout.splitlines() if " " in line)
    assert out["by-value"] == "3"
    assert "passed where the address of a variable holding one is expected" in out["message"]
    assert out["foreign"] == "3"
    assert out["twice"] == "3"
    assert out["after-free"] == "3"
    assert r.stdout.rstrip().endswith("alive")


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_model_description_declares_dependencies_ranges_units_and_provenance(version):
    md = read_model_description(FMUS[version])
    assert md.generationTool.startswith("efsi-fmu ")
    assert md.generationDateAndTime and md.license and md.copyright and md.author
    variables = {v.name: v for v in md.modelVariables}
    # No output depends directly on the input: no algebraic loop for an importer to break.
    assert md.outputs and all(u.dependencies == [] for u in md.outputs)
    for name, lo, hi in [("base_acceleration", -1000.0, 1000.0), ("solid.velocity[1]", -100.0, 100.0),
                         ("grid.nr", 2, 1000), ("max_solver_steps_per_step", 1, 10**9)]:
        assert (float(variables[name].min), float(variables[name].max)) == (lo, hi), name
    # Open bounds (G > 0, a radius > 0, a CFL number > 0, refused at 0 when initialisation
    # ends): declared as the smallest value accepted, the smallest double above 0.
    for name in ("solid.law.parameters.G", "solid.shape.radius", "time.cfl"):
        assert float(variables[name].min) == 5e-324, name
    assert variables["solid.law.parameters.G"].unit == "Pa"
    import zipfile
    names = zipfile.ZipFile(FMUS[version]).namelist()
    assert "documentation/index.html" in names
    assert "documentation/licenses/license.txt" in names
    # Stripped: the whole FMU well under 4 MB.
    assert os.path.getsize(FMUS[version]) < 4e6


# --- A second importer: Ecos (ecospy, its own FMI loader fmi4c) ----------------------------------


@pytest.fixture(scope="module")
def ecos():
    # ecospy's library links Intel TBB's runtime (libtbb.so.12). The `tbb` wheel of
    # requirements.txt puts it in the environment's lib/, which is on no library path: load it
    # first, so the dynamic linker finds it loaded by its soname, and no system package is needed.
    tbb = os.path.join(sys.prefix, "lib", "libtbb.so.12")
    if os.path.exists(tbb):
        ctypes.CDLL(tbb, mode=ctypes.RTLD_GLOBAL)
    try:
        import ecospy
        from ecospy.lib import EcosLib
    except OSError as e:
        pytest.fail(
            f"ecospy's library does not load ({e}): it needs libtbb.so.12, which the `tbb` wheel "
            f"of tests/python/requirements.txt installs into {sys.prefix}/lib"
        )
    EcosLib.set_log_level("warn")
    return ecospy


def ecos_run(ecospy, path, h, n, params, a):
    """The FMU in Ecos: fixed steps h (Ecos advances its clock by t += h), the input a(k) set
    before step k; the outputs after each step."""
    ss = ecospy.EcosSimulationStructure()
    ss.add_model("sphere", str(path))
    if params:
        ss.add_parameter_set("p", {f"sphere::{k}": v for k, v in params.items()})
    rows = []
    with ecospy.EcosSimulation(structure=ss, step_size=h) as sim:
        sim.init(parameter_set="p" if params else None)
        for k in range(n):
            sim.set_real("sphere::base_acceleration", a(k))
            sim.step()
            rows.append(tuple(sim.get_real(f"sphere::{o}") for o in OUTPUTS[:-1])
                        + (sim.get_integer("sphere::steps"), sim.get_time()))
        sim.terminate()
    return rows


def fmpy_run(version, unzipped, h, n, params, a):
    """The same calls through fmpy's low-level classes: doStep(t, h) with t += h."""
    fmu, vr = slave(version, unzipped, **params)
    t, rows = 0.0, []
    for k in range(n):
        (fmu.setReal if version == "fmi2" else fmu.setFloat64)([vr["base_acceleration"]], [a(k)])
        fmu.doStep(t, h)
        t += h
        rows.append(tuple(read(version, fmu, vr)) + (t,))
    fmu.terminate()
    fmu.freeInstance()
    return rows


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
@pytest.mark.parametrize("h", [1e-3, 2.0**-10], ids=["1ms", "2pow-10s"])
def test_two_importers_agree_bit_for_bit(version, h, ecos, unzipped):
    """70 ms of the sphere (the FMU's default parameters, 10 cells per radius: impact and
    rebound), a shaking substrate as input, in fmpy and in Ecos: the same outputs, bit for bit."""
    n = math.ceil(0.07 / h)
    params = {"grid.nr": 23, "grid.nz": 47, "solid.shape.center[1]": 0.0573}  # the defaults
    a = lambda k: 20.0 * math.sin(0.3 * k)  # noqa: E731
    in_ecos = ecos_run(ecos, FMUS[version], h, n, params, a)
    in_fmpy = fmpy_run(version, unzipped, h, n, params, a)
    assert in_ecos == in_fmpy
    force = [r[OUTPUTS.index("contact_force")] for r in in_fmpy]
    velocity = [r[OUTPUTS.index("solid_v")] for r in in_fmpy]
    assert max(force) > 1.0 and velocity[-1] > 0.3  # it hits, and is on its way up by 70 ms


# --- FMI compatibility information: the reference result (FMI Cross-Check layout) ---------------

COMPAT = REPO / "fmu" / "compat"


def read_opt(path):
    return {k.strip(): float(v) for k, v in (line.split(",") for line in path.read_text().splitlines() if line.strip())}


def reference_input(times):
    """The substrate's acceleration of the reference run: still for 10 ms, then shaken at 40 Hz
    with 50 m/s² (about 5 g)."""
    return [0.0 if t < 0.01 else 50.0 * math.sin(2 * math.pi * 40.0 * (t - 0.01)) for t in times]


REFERENCE_OUTPUTS = OUTPUTS


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_reference_result_is_reproduced(version):
    """`fmu/compat/sphere_impact/`: the run of `_ref.opt` with the input `_in.csv` gives
    `_ref.csv` — the reference result an importer compares with (FMI Cross-Check layout: at most
    10 variables). `EFSI_UPDATE_FMU_REFERENCE=1` writes the files from the FMI 2.0 run."""
    folder = COMPAT / "sphere_impact"
    update = os.environ.get("EFSI_UPDATE_FMU_REFERENCE") == "1" and version == "fmi2"
    if update:
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "sphere_impact_ref.opt").write_text(
            "StartTime, 0.0\nStopTime, 0.07\nStepSize, 0.001\nRelTol, 1e-06\n")
        times = [k * 0.001 for k in range(71)]
        with open(folder / "sphere_impact_in.csv", "w") as f:
            f.write('"time","base_acceleration"\n')
            for t, a in zip(times, reference_input(times)):
                f.write(f"{t!r},{a!r}\n")
    opt = read_opt(folder / "sphere_impact_ref.opt")
    with open(folder / "sphere_impact_in.csv") as f:
        rows = list(csv.reader(f))
    signal = np.array([tuple(float(x) for x in r) for r in rows[1:]],
                      dtype=[("time", np.float64), ("base_acceleration", np.float64)])
    r = simulate_fmu(FMUS[version], start_time=opt["StartTime"], stop_time=opt["StopTime"],
                     output_interval=opt["StepSize"], input=signal, output=REFERENCE_OUTPUTS)
    if update:
        with open(folder / "sphere_impact_ref.csv", "w") as f:
            f.write(",".join(f'"{n}"' for n in ["time"] + REFERENCE_OUTPUTS) + "\n")
            for row in r:
                f.write(",".join(repr(float(x)) if n != "steps" else str(int(x))
                                 for n, x in zip(["time"] + REFERENCE_OUTPUTS, row)) + "\n")
    with open(folder / "sphere_impact_ref.csv") as f:
        ref = list(csv.DictReader(f))
    assert len(ref[0]) <= 10 and len(ref) == len(r)
    for name in ["time"] + REFERENCE_OUTPUTS:
        want = np.array([float(row[name]) for row in ref])
        assert np.array_equal(r[name], want), (
            f"{name} differs from fmu/compat/sphere_impact/sphere_impact_ref.csv; if the change is "
            "meant, regenerate it: EFSI_UPDATE_FMU_REFERENCE=1 and run this test")
    assert r["contact_force"].max() > 1.0


# --- Any scene as an FMU: `cargo xtask fmu SCENE --parameter … --input … --output …` -----------


def efsi_run_case(tmp_path, case, edits, sets=()):
    """`efsi run` of `cases/<case>.ron` with its output schedule edited (`edits`: text
    replacements, so that it lands on the communication points only) and `--set` overrides."""
    text = (REPO / "cases" / f"{case}.ron").read_text()
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / f"{case}.ron"
    path.write_text(text)
    out = tmp_path / "out"
    env = dict(os.environ, EFSI_LAW_PATH=str(REPO / "target/fmu-release"))
    cmd = [EFSI, "run", str(path), "--out", str(out), "-q"]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True, env=env)
    with open(out / "probes.csv") as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def ecos_scene(ecospy, path, h, n, params, inputs, outputs):
    """A scene FMU in Ecos: fixed steps h, `inputs(k)` (a dict) set before step k."""
    ss = ecospy.EcosSimulationStructure()
    ss.add_model("m", str(path))
    if params:
        ss.add_parameter_set("p", {f"m::{k}": v for k, v in params.items()})
    rows = []
    with ecospy.EcosSimulation(structure=ss, step_size=h) as sim:
        sim.init(parameter_set="p" if params else None)
        for k in range(n):
            for name, v in inputs(k).items():
                sim.set_real(f"m::{name}", v)
            sim.step()
            rows.append(tuple(sim.get_real(f"m::{o}") for o in outputs))
        sim.terminate()
    return rows


def fmpy_scene(path, h, n, params, inputs, outputs):
    """The same calls through fmpy's FMU2Slave / FMU3Slave (doStep(t, h), t += h)."""
    unzipped = extract(path)
    try:
        return fmpy_slave_rows(unzipped, h, n, params, inputs, outputs)
    finally:
        import shutil

        shutil.rmtree(unzipped, ignore_errors=True)


def fmpy_slave_rows(unzipped, h, n, params, inputs, outputs):
    """`fmpy_scene` on an extracted FMU."""
    md = read_model_description(unzipped)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmi2 = md.fmiVersion == "2.0"
    fmu = (FMU2Slave if fmi2 else FMU3Slave)(
        guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="m")
    fmu.instantiate()
    if fmi2:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
    else:
        fmu.enterInitializationMode(startTime=0.0)
    for k, v in params.items():
        (fmu.setReal if fmi2 else fmu.setFloat64)([vr[k]], [v])
    fmu.exitInitializationMode()
    t, rows = 0.0, []
    for k in range(n):
        for name, v in inputs(k).items():
            (fmu.setReal if fmi2 else fmu.setFloat64)([vr[name]], [v])
        fmu.doStep(t, h)
        t += h
        rows.append(tuple((fmu.getReal if fmi2 else fmu.getFloat64)([vr[o] for o in outputs])))
    fmu.terminate()
    fmu.freeInstance()
    return rows


@pytest.mark.parametrize("fmu", ["oscillating_couette.fmu", "oscillating_couette_fmi3.fmu"])
def test_couette_fmu_with_the_wall_speed_as_a_parameter(fmu, ecos, tmp_path):
    """`cargo xtask fmu cases/oscillating_couette.ron --parameter boundaries.y_max.speed=m/s
    --output u_interface=m/s`: the wall's speed amplitude set to 0.5, the interface velocity bit
    for bit `efsi run --set boundaries.y_max.speed=0.5` of the same scene, in fmpy and Ecos."""
    h, n = 2.0**-7, 64  # 0.5 s
    path = FMU_DIR / fmu
    params = {"boundaries.y_max.speed": 0.5}
    r = simulate_fmu(path, stop_time=n * h, output_interval=h, start_values=params,
                     output=["u_interface"])
    p = efsi_run_case(tmp_path, "oscillating_couette",
                      [("vtk_every: 0.4,", ""), ("probe_every: 0.01,", f"probe_every: {h!r},"),
                       ("end: 4.8,", f"end: {n * h!r},"),
                       ("at: [0.5, 1.0, 2.0, 2.8, 4.0, 4.8]", "at: [0.5]")],
                      sets=["boundaries.y_max.speed=0.5"])
    assert np.array_equal(r["time"], p["t"])
    assert np.array_equal(r["u_interface"], p["u_interface"])
    both = [ecos_scene(ecos, path, h, n, params, lambda k: {}, ["u_interface"]),
            fmpy_scene(path, h, n, params, lambda k: {}, ["u_interface"])]
    assert both[0] == both[1] == [(x,) for x in r["u_interface"][1:]]
    # The parameter acts: at the full amplitude the interface moves about twice as fast.
    full = simulate_fmu(path, stop_time=n * h, output_interval=h, output=["u_interface"])
    assert full["u_interface"][-1] == pytest.approx(2 * r["u_interface"][-1], rel=0.05)
    assert abs(r["u_interface"]).max() > 0.05


@pytest.mark.parametrize("fmu", ["disk_in_cavity.fmu", "disk_in_cavity_fmi3.fmu"])
def test_disk_in_a_cavity_fmu_with_the_lid_speed_as_an_input(fmu, ecos, tmp_path):
    """`cargo xtask fmu cases/disk_in_cavity.ron --input boundaries.y_max.speed=m/s`: with the
    lid at the scene's speed, every probe bit for bit `efsi run` of the same scene; with a
    varying lid speed, fmpy and Ecos agree bit for bit, and the disk moves differently."""
    h, n = 2.0**-5, 4  # 0.125 s
    path = FMU_DIR / fmu
    outputs = ["solid_x", "solid_y", "solid_u", "solid_v", "kinetic_energy", "elastic_energy"]
    steady = lambda k: {"boundaries.y_max.speed": 1.0}  # noqa: E731
    r = fmpy_scene(path, h, n, {}, steady, outputs)
    p = efsi_run_case(tmp_path, "disk_in_cavity",
                      [("probe_every: 0.02,", f"probe_every: {h!r},"),
                       ("end: 20.0,", f"end: {n * h!r},")])
    for k, name in enumerate(outputs):
        assert [row[k] for row in r] == list(p[name][1:]), name
    shaken = lambda k: {"boundaries.y_max.speed": 1.0 + 0.5 * math.sin(k)}  # noqa: E731
    in_fmpy = fmpy_scene(path, h, n, {}, shaken, outputs)
    assert ecos_scene(ecos, path, h, n, {}, shaken, outputs) == in_fmpy
    assert in_fmpy[-1][outputs.index("kinetic_energy")] != r[-1][outputs.index("kinetic_energy")]


# The reference results of the scene FMUs (FMI Cross-Check layout, like the sphere's).
SCENE_REFERENCES = {
    # model: (stop, step, input (name, function of t) or None, outputs, start values)
    "oscillating_couette": (0.5, 2.0**-7, None, ["u_interface", "steps"], {}),
    "disk_in_cavity": (0.125, 2.0**-5,
                       ("boundaries.y_max.speed", lambda t: 1.0 if t < 0.0625 else 1.5),
                       ["solid_x", "solid_y", "solid_u", "solid_v", "kinetic_energy",
                        "elastic_energy", "steps"], {}),
}


@pytest.mark.parametrize("suffix", ["", "_fmi3"])
@pytest.mark.parametrize("model", sorted(SCENE_REFERENCES))
def test_scene_fmu_reference_results_are_reproduced(model, suffix):
    """`fmu/compat/<model>/`: `_ref.opt`, `_in.csv` (where the FMU has an input) and
    `_ref.csv`, reproduced bit for bit by both FMUs in fmpy. `EFSI_UPDATE_FMU_REFERENCE=1`
    writes them from the FMI 2.0 run (start values: the FMU's, i.e. the scene's)."""
    stop, step, inp, outputs, start = SCENE_REFERENCES[model]
    folder = COMPAT / model
    update = os.environ.get("EFSI_UPDATE_FMU_REFERENCE") == "1" and suffix == ""
    n = round(stop / step)
    times = [k * step for k in range(n + 1)]
    if update:
        folder.mkdir(parents=True, exist_ok=True)
        (folder / f"{model}_ref.opt").write_text(
            f"StartTime, 0.0\nStopTime, {stop!r}\nStepSize, {step!r}\nRelTol, 1e-06\n")
        if inp:
            with open(folder / f"{model}_in.csv", "w") as f:
                f.write(f'"time","{inp[0]}"\n')
                for t in times:
                    f.write(f"{t!r},{inp[1](t)!r}\n")
    opt = read_opt(folder / f"{model}_ref.opt")
    signal = None
    if inp:
        with open(folder / f"{model}_in.csv") as f:
            rows = list(csv.reader(f))
        signal = np.array([tuple(float(x) for x in r) for r in rows[1:]],
                          dtype=[("time", np.float64), (inp[0], np.float64)])
    r = simulate_fmu(FMU_DIR / f"{model}{suffix}.fmu", start_time=opt["StartTime"],
                     stop_time=opt["StopTime"], output_interval=opt["StepSize"], input=signal,
                     start_values=start, output=outputs)
    if update:
        with open(folder / f"{model}_ref.csv", "w") as f:
            f.write(",".join(f'"{n}"' for n in ["time"] + outputs) + "\n")
            for row in r:
                f.write(",".join(repr(float(x)) if n != "steps" else str(int(x))
                                 for n, x in zip(["time"] + outputs, row)) + "\n")
    with open(folder / f"{model}_ref.csv") as f:
        ref = list(csv.DictReader(f))
    assert len(ref[0]) <= 10 and len(ref) == len(r)
    for name in ["time"] + outputs:
        want = np.array([float(row[name]) for row in ref])
        assert np.array_equal(r[name], want), f"{name} differs from fmu/compat/{model}/{model}_ref.csv"


@pytest.mark.parametrize("fmu", ["falling_drop_3d.fmu", "falling_drop_3d_fmi3.fmu"])
def test_a_three_dimensional_drop_fmu_equals_efsi_run(fmu, ecos, tmp_path):
    """`cargo xtask fmu cases/falling_drop_3d.ron --parameter grid.nx --parameter grid.ny
    --parameter grid.nz`: the 3-D drop (two symmetry planes) at 8 x 16 x 8 cells, every probe
    column (solid_z and solid_w among them) bit for bit `efsi run --set` of the same scene with
    its probes at the communication points, in fmpy and in Ecos."""
    h, n = 2.0**-5, 8  # 0.25 s, four fixed steps per communication step
    path = FMU_DIR / fmu
    grid = {"grid.nx": 8, "grid.ny": 16, "grid.nz": 8}
    outputs = ["solid_volume", "solid_x", "solid_y", "solid_z", "solid_u", "solid_v", "solid_w",
               "max_divergence"]
    r = simulate_fmu(path, stop_time=n * h, output_interval=h, start_values=grid,
                     output=outputs + ["steps"])
    p = efsi_run_case(tmp_path, "falling_drop_3d",
                      [("probe_every: 0.03125,", f"probe_every: {h!r},"),
                       ("end: 1.0,", f"end: {n * h!r},")],
                      sets=[f"{k}={v}" for k, v in grid.items()])
    assert list(p) == ["t"] + outputs
    assert np.array_equal(r["time"], p["t"])
    for name in outputs:
        assert np.array_equal(r[name], p[name]), name
    assert list(r["steps"]) == [4 * k for k in range(n + 1)]
    assert r["solid_v"][-1] < -0.1  # the drop falls
    in_ecos = ecos_scene(ecos, path, h, n, grid, lambda k: {}, outputs)
    assert in_ecos == [tuple(r[o][k] for o in outputs) for k in range(1, n + 1)]


@pytest.mark.parametrize("fmu", ["sphere_impact_3d.fmu", "sphere_impact_3d_fmi3.fmu"])
def test_a_three_dimensional_elastic_sphere_fmu_equals_efsi_run(fmu, ecos, tmp_path):
    """`cargo xtask fmu cases/sphere_impact_3d.ron --parameter grid.nx --parameter grid.ny
    --parameter grid.nz --parameter solid.shape.center[1]`: the 3-D neo-Hookean sphere (a
    quarter domain, two symmetry planes) at 6 cells per radius, released 5.8 mm above the
    substrate, through the impact: every probe column bit for bit `efsi run --set` of the same
    scene with its probes at the communication points, in fmpy and in Ecos."""
    h, n = 2.0**-10, 10  # through the impact (contact from ≈ 5 ms)
    path = FMU_DIR / fmu
    params = {"grid.nx": 14, "grid.ny": 28, "grid.nz": 14, "solid.shape.center[1]": 0.025}
    outputs = ["solid_x", "solid_y", "solid_z", "solid_u", "solid_v", "solid_w",
               "solid_volume", "kinetic_energy", "contact_force", "contact_radius",
               "solid_bottom", "solid_top", "solid_pieces", "solid_largest_piece", "max_speed"]
    r = simulate_fmu(path, stop_time=n * h, output_interval=h, start_values=params,
                     output=outputs + ["steps"])
    p = efsi_run_case(tmp_path, "sphere_impact_3d",
                      [("probe_every: 0.0002,", f"probe_every: {h!r},"),
                       ("end: 0.06,", f"end: {n * h!r},"),
                       ("vtk_every: 0.005,", "")],
                      sets=[f"{k}={v}" for k, v in params.items()])
    assert list(p) == ["t"] + outputs
    assert np.array_equal(r["time"], p["t"])
    for name in outputs:
        assert np.array_equal(r[name], p[name]), name
    assert np.all(np.diff(r["steps"]) > 0)
    assert r["contact_force"].max() > 0.0  # the run reaches the impact
    in_ecos = ecos_scene(ecos, path, h, n, params, lambda k: {}, outputs)
    assert in_ecos == [tuple(r[o][k] for o in outputs) for k in range(1, n + 1)]
