#!/usr/bin/env python3
"""The help and docs test (ctest cli_docs): what README.md and docs/*.md tell a user to type works.

1. Every subcommand's --help exits 0 and says what the subcommand does; the commands that handle every kind
   do not describe themselves as texton-only.
2. Every `stex` command shown in a ```sh block (and in a plain ``` block) of README.md and docs/*.md:
   - every option it names, optional ones in [brackets] included, is an option of its subcommand's --help;
   - it runs, in document order, in one scratch directory per page, with the inputs the page assumes
     (data/, gravel.png, bricks.png, ..., below) and the files earlier commands of the page wrote, and exits 0.
     Optional [groups] are left out, as a first-time reader types it. A few commands are run with less work
     (REDUCED: the whole benchmark, 200 corpus exemplars, S2's 1000-initialisation report) or on this machine's
     device (`--device gpu`); each entry says why, and an entry that no longer matches a command of the docs
     fails the test, so the table cannot go stale.
   The page's other shell lines run too when they make an input (echo/cat > file), call OpenImageIO's tools
   on the plugin, or query `stex serve` (curl); the rest (package installs, builds, Slurm) are listed in
   NOT_RUN with the test that covers them.

Usage: docs_commands_test.py --stex PATH --source DIR --scratch DIR [--imageio DIR]
"""
import argparse
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

# Commands run with less work than the docs show: doc command (comments and [optional] groups removed) ->
# the command run, and why. Options are checked on the doc command as written.
REDUCED = {
    "stex bench":
        ("stex bench --mni 30 --support 64 --size 256 --compare splat --no-table1 --no-quality --repeat 1",
         "the default run takes about a minute of 2 cores"),
    "stex bench --mni 1,2,4,8,16,30,60,120 --json out.json --csv out.csv --svg plot.svg --markdown tables.md":
        ("stex bench --mni 1,30 --support 64 --size 256 --compare splat --no-table1 --repeat 1 --json out.json "
         "--csv out.csv --svg plot.svg --markdown tables.md", "eight MNI values of the full table take minutes"),
    "stex periods --corpus 200": ("stex periods --corpus 6", "200 exemplars take about a minute"),
    "stex s2-report --out docs/s2 --exemplar data/gravel.png --crop 128 --inits 1000 --iterations 1000 "
    "--radius 15 --radii 5,15,25 --fig5-iterations 1000 --threads 1 --seed 0 --sample 256":
        ("stex s2-report --out docs/s2 --exemplar data/gravel.png --crop 32 --inits 2 --iterations 3 --radius 5 "
         "--radii 3,5 --fig5-iterations 3 --threads 1 --seed 0 --sample 32",
         "S2's figures take about an hour at the published counts"),
    "stex render rot.stex -o rot.exr --size 4096x4096 --tile-size 1024 --seed 3 --mni 16":
        ("stex render rot.stex -o rot.exr --size 512x512 --tile-size 256 --seed 3 --mni 16",
         "16 Mpixel of per-pixel cs-rpn take over a minute on a CPU device"),
    "stex selftest --device gpu --json > selftest.json || exit 1":
        ("stex selftest --json --only texton > selftest.json || exit 1",
         "no GPU here: the default device instead, and one kind's rows (every row takes about 20 s of 2 cores)"),
    "stex selftest": ("stex selftest --only texton --only lrp", "every row takes about 20 s of 2 cores"),
}

# What a page assumes a reader has done before its commands, where the page shows it with a line this test does
# not run (NOT_RUN), or on another page.
SETUP = {
    "docs/farm.md": [  # the Slurm array of its first block, as one local process with the same tile names
        "stex analyze data/gravel.png -o gravel.stex --method texton",
        "stex render gravel.stex -o 'out/gravel_{tx}_{ty}.exr' --size 320x256 --tile-size 128",
    ],
    "docs/oiio-plugin.md": ["stex analyze data/gravel.png -o gravel.stex --method texton"],  # the README's first model
}

# Shell lines of the docs that this test does not run, by their first word(s), and what covers them.
NOT_RUN = {
    "make": "the README's two commands are what CI runs (.ci/run)",
    "cmake": "CI builds the tree; embedding.md's install is ctest embed_install",
    "scripts/install-deps.sh": "CI's first step",
    "scripts/farm/slurm_array.sh": "ctest slurm (a one-node cluster)",
    "cd build && STEX_TEST_DEVICE=gpu ctest": "runs this suite",
    "STEX_TEST_DEVICE=1 ctest": "runs this suite",
    "uptime": "a benchmarking habit",
    "build/cli/stex bench": "docs/bench's full run (tens of minutes); `stex bench` is run above",
    "build/benchmarks/stex_bench": "the kernel benchmarks (benchmarks/, run by ctest bench_smoke)",
}

# Subcommands that handle every kind: their --help must not call them texton-only.
EVERY_KIND = ["analyze", "render", "serve", "selftest"]


def fail(msg):
    print("FAIL: " + msg, flush=True)
    fail.count += 1


fail.count = 0


def sh_blocks(path):
    """(line number, text) of the shell lines of ```sh and plain ``` blocks; continuations joined."""
    lines = path.read_text(encoding="utf-8").split("\n")
    fence, out, i = None, [], 0
    while i < len(lines):
        s = lines[i].strip()
        if s.startswith("```"):
            fence = None if fence is not None else s[3:].strip()
            if fence is None:
                out.append((i + 1, None))  # block end
            i += 1
            continue
        # ```sh blocks: every line; plain ``` blocks (diagrams, output, a few commands): the stex commands
        if (fence == "sh" and s and not s.startswith("#")) or (fence == "" and s.startswith("stex ")):
            n = i + 1
            if s.startswith("cat >") and "<<" in s:  # here-document: the lines up to its delimiter
                delim = s.split("<<", 1)[1].strip().strip("'\"")
                body = [s]
                while i + 1 < len(lines) and lines[i + 1].strip() != delim:
                    i += 1
                    body.append(lines[i])
                i += 1
                body.append(delim)
                out.append((n, "\n".join(body)))
            else:
                while s.endswith("\\") and i + 1 < len(lines):
                    i += 1
                    s = s[:-1].rstrip() + " " + lines[i].strip()
                out.append((n, s))
        i += 1
    return out


def strip_comment(s):
    """The line without its trailing `# comment` (a # after whitespace, outside quotes)."""
    quote = None
    for k, c in enumerate(s):
        if quote:
            if c == quote:
                quote = None
        elif c in "'\"":
            quote = c
        elif c == "#" and k > 0 and s[k - 1].isspace():
            return s[:k].rstrip()
    return s.rstrip()


def drop_optional(s):
    """Without its [optional] groups (and a trailing ... after one)."""
    out, depth = [], 0
    for c in s:
        if c == "[":
            depth += 1
        elif c == "]" and depth:
            depth -= 1
        elif depth == 0:
            out.append(c)
    return re.sub(r"\s+", " ", re.sub(r"(^|\s)\.\.\.(?=\s|$)", " ", "".join(out))).strip()


def options_of(s):
    return set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", s))


def make_inputs(d, source):
    """The files the pages assume a reader has beside them."""
    import numpy as np
    import OpenImageIO as oiio

    data = (source / "data").resolve()
    os.symlink(data, d / "data")
    for name, src in [("gravel.png", "gravel.png"), ("exemplar.png", "gravel.png"), ("bricks.png", "brick.png"),
                      ("tiles.png", "tiles_stone.png"), ("wood.png", "grass.png")]:
        shutil.copy(data / src, d / name)

    def write(name, pixels):
        spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2],
                              "float" if name.endswith(".exr") else "uint8")
        out = oiio.ImageOutput.create(name)
        assert out and out.open(str(d / name), spec), oiio.geterror()
        out.write_image(pixels if name.endswith(".exr") else np.clip(pixels * 255 + 0.5, 0, 255).astype(np.uint8))
        out.close()

    # A centred PSD image: a ring at 0.1 cycles/pixel.
    y, x = np.mgrid[-32:32, -32:32] / 64.0
    ring = np.exp(-((np.hypot(x, y) - 0.1) / 0.02) ** 2)[:, :, None]
    write("psd.png", ring)
    write("my_psd.png", ring)
    write("map.png", np.tile(np.linspace(0, 1, 64), (64, 1))[:, :, None])  # a mixing map: a horizontal ramp
    v, u = np.mgrid[0:96, 0:128].astype(np.float32)  # a UV map: a rotated, stretched plane
    write("uv.exr", np.stack([1.5 * u + 0.3 * v, -0.2 * u + 1.1 * v, np.zeros_like(u)], axis=2))
    # A small closed mesh with UVs: an octahedron subdivided once (PLY and OBJ).
    verts = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    faces = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
    with open(d / "bunny.ply", "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
                "element face %d\nproperty list uchar int vertex_indices\nend_header\n" % (len(verts), len(faces)))
        f.writelines("%g %g %g\n" % p for p in verts)
        f.writelines("3 %d %d %d\n" % t for t in faces)
    with open(d / "bunny.obj", "w") as f:
        f.writelines("v %g %g %g\n" % p for p in verts)
        f.writelines("vt %g %g\n" % (0.5 + 0.45 * p[0], 0.5 + 0.45 * p[1]) for p in verts)
        f.writelines("f %d/%d %d/%d %d/%d\n" % (t[0] + 1, t[0] + 1, t[1] + 1, t[1] + 1, t[2] + 1, t[2] + 1)
                     for t in faces)
    (d / "models").mkdir()
    (d / "out").mkdir()


class Page:
    """One page's commands, run in order in one scratch directory."""

    def __init__(self, args, page, scratch):
        self.args, self.page, self.dir = args, page, scratch
        self.serve = None
        self.port = None
        self.env = dict(os.environ)
        self.env["PATH"] = str(Path(args.stex).resolve().parent) + os.pathsep + self.env["PATH"]
        if args.imageio:
            self.env["OIIO_LIBRARY_PATH"] = str(Path(args.imageio).resolve())

    def run(self, where, cmd, timeout=600):
        t0 = time.monotonic()
        r = subprocess.run(["bash", "-c", "set -o pipefail\n" + cmd], cwd=self.dir, env=self.env,
                           capture_output=True, text=True, timeout=timeout)
        dt = time.monotonic() - t0
        print("  %5.1f s  exit %d  %s" % (dt, r.returncode, cmd.split("\n")[0][:150]), flush=True)
        if r.returncode != 0:
            fail("%s: `%s` exits %d\n%s%s" % (where, cmd, r.returncode, r.stdout[-2000:], r.stderr[-2000:]))
        return r

    def start_serve(self, where, cmd):
        port_file = self.dir / "serve.port"
        cmd = re.sub(r"--port \d+", "", cmd) + " --port 0 --port-file serve.port"
        print("  start  %s" % cmd, flush=True)
        self.serve = subprocess.Popen(shlex.split(cmd), cwd=self.dir, env=self.env, stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT, text=True)
        for _ in range(600):
            if port_file.exists() and port_file.read_text().strip():
                self.port = port_file.read_text().strip()
                return
            if self.serve.poll() is not None:
                break
            time.sleep(0.1)
        fail("%s: `%s` did not start listening\n%s" % (where, cmd, self.stop_serve(where)))

    def stop_serve(self, where):
        if not self.serve:
            return ""
        if self.serve.poll() is None:
            self.serve.send_signal(signal.SIGTERM)
        try:
            out, _ = self.serve.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            self.serve.kill()
            out, _ = self.serve.communicate()
            fail("%s: stex serve did not stop on SIGTERM" % where)
        if self.serve.returncode != 0:
            fail("%s: stex serve exits %d on SIGTERM\n%s" % (where, self.serve.returncode, out[-2000:]))
        self.serve = None
        return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--stex", required=True)
    ap.add_argument("--source", required=True)
    ap.add_argument("--scratch", required=True)
    ap.add_argument("--imageio")
    args = ap.parse_args()
    source, scratch = Path(args.source), Path(args.scratch)
    shutil.rmtree(scratch, ignore_errors=True)
    scratch.mkdir(parents=True)

    # 1. --help of every subcommand.
    top = subprocess.run([args.stex, "--help"], capture_output=True, text=True)
    if top.returncode != 0:
        fail("stex --help exits %d" % top.returncode)
    subs = re.findall(r"^  ([a-z][a-z0-9-]*)\s", top.stdout.split("Subcommands:", 1)[-1], re.M)
    if len(subs) < 15:
        fail("stex --help lists %d subcommands: %s" % (len(subs), subs))
    helps, help_options = {}, {}
    for sub in subs:
        r = subprocess.run([args.stex, sub, "--help"], capture_output=True, text=True)
        helps[sub] = r.stdout + r.stderr
        help_options[sub] = options_of(helps[sub])
        first = r.stdout.strip().split("\n")[0] if r.stdout.strip() else ""
        if r.returncode != 0 or len(first) < 20 or "Usage:" in first:
            fail("stex %s --help: exit %d, first line %r" % (sub, r.returncode, first))
        if "--help" not in r.stdout:
            fail("stex %s --help lists no options" % sub)
    for sub in EVERY_KIND:
        if sub in helps and re.search(r"(of|into) a texton noise model", helps[sub]):
            fail("stex %s --help calls it texton-only: %s" % (sub, helps[sub].split("\n")[0]))
    global_options = options_of(top.stdout)

    # 2. The docs' commands.
    pages = [source / "README.md"] + sorted((source / "docs").glob("*.md"))
    used_reduced, used_not_run, oiio_run = set(), set(), set()
    ran = 0
    for page in pages:
        lines = sh_blocks(page)
        if not any(t for _, t in lines):
            continue
        print("%s" % page.relative_to(source), flush=True)
        d = scratch / page.stem
        d.mkdir()
        make_inputs(d, source)
        p = Page(args, page, d)
        for cmd in SETUP.get(str(page.relative_to(source)), []):
            p.run("%s (setup)" % page.relative_to(source), cmd)
        for n, text in lines:
            where = "%s:%d" % (page.relative_to(source), n)
            if text is None:  # end of a block: a server started there stops
                p.stop_serve(where)
                continue
            line = strip_comment(text)
            if line.startswith("["):  # a synopsis continued: its options were checked with the first line
                continue
            if line.startswith("stex "):
                words = line.split()
                sub = words[1]
                if sub not in helps:
                    fail("%s: `%s`: no subcommand %r" % (where, line, sub))
                    continue
                for opt in sorted(options_of(line)):
                    if opt not in help_options[sub] and opt not in global_options:
                        fail("%s: %s is not an option of `stex %s` (--help)" % (where, opt, sub))
                cmd = drop_optional(line)
                if cmd in REDUCED:
                    used_reduced.add(cmd)
                    cmd = REDUCED[cmd][0]
                if sub == "serve":
                    p.start_serve(where, cmd)
                else:
                    p.run(where, cmd)
                ran += 1
                continue
            key = next((k for k in NOT_RUN if line.startswith(k)), None)
            if key:
                used_not_run.add(key)
                continue
            if line.startswith("export OIIO_LIBRARY_PATH="):
                continue  # set from --imageio
            if line.startswith("curl ") and p.port:
                p.run(where, line.replace("127.0.0.1:8080", "127.0.0.1:" + p.port))
                ran += 1
                continue
            first = line.split()[0]
            if first in ("oiiotool", "iinfo", "maketx") or first.startswith("STEX_IMAGEIO_OPTIONS="):
                if line in oiio_run:  # the same line on an earlier page: it only writes a file no line reads
                    continue
                oiio_run.add(line)
            if line.startswith(("echo ", "cat >")) or (first in ("oiiotool", "iinfo", "maketx") and args.imageio) \
                    or (first.startswith("STEX_IMAGEIO_OPTIONS=") and args.imageio):
                p.run(where, line)
                ran += 1
                continue
            fail("%s: a shell line this test neither runs nor lists in NOT_RUN: %s" % (where, line))
        p.stop_serve(str(page))

    for k in REDUCED:
        if k not in used_reduced:
            fail("REDUCED entry matches no command of the docs (stale): %s" % k)
    for k in NOT_RUN:
        if k not in used_not_run:
            fail("NOT_RUN entry matches no line of the docs (stale): %s" % k)
    print("%d commands run, %d subcommands' --help checked, %d failures" % (ran, len(subs), fail.count))
    return 1 if fail.count else 0


if __name__ == "__main__":
    sys.exit(main())
