"""pytest set-up of the Python module's tests: the OpenCL device of every test is STEX_TEST_DEVICE (the
syntax of --device; unset or empty = the default device), as in the C++ test binaries (tests/test_device.h).
The session starts by printing "stex tests: device [index] NAME (PLATFORM)", taken from `stex info --json`
(STEX_CLI, set by ctest), and stops (exit 1) when an explicit STEX_TEST_DEVICE selects no device."""
import json
import os
import subprocess

import pytest


def device_spec():
    return os.environ.get("STEX_TEST_DEVICE", "")


def describe_device(spec):
    """'[index] NAME (PLATFORM)' of the device `spec` selects, or raises RuntimeError with stex's message."""
    cli = os.environ.get("STEX_CLI")
    if not cli:
        import stex  # without the CLI: the name only

        return stex.Context(spec).device_name
    env = dict(os.environ, STEX_DEVICE=spec)
    r = subprocess.run([cli, "info", "--json"], env=env, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(r.stderr.strip() or "stex info exited with %d" % r.returncode)
    info = json.loads(r.stdout)
    index = info["selected_device"] if info.get("selected_device") is not None else info["default_device"]
    device = info["devices"][index]
    platform = info["platforms"][device["platform"]]["name"]
    return "[%d] %s (%s)" % (index, device["name"], platform)


def pytest_sessionstart(session):
    spec = device_spec()
    try:
        line = "stex tests: device " + describe_device(spec)
    except Exception as exc:  # noqa: BLE001 (any failure to resolve the device)
        if spec:
            pytest.exit("stex tests: STEX_TEST_DEVICE='%s' selects no device: %s" % (spec, exc), returncode=1)
        line = "stex tests: device none (%s)" % exc
    session.config.pluginmanager.getplugin("terminalreporter").write_line(line)
