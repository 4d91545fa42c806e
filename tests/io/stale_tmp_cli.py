#!/usr/bin/python3
"""A `volvis convert` killed mid-write leaves a temporary beside OUT; the
next write of OUT removes it, and never the temporary of a writer that
still runs.

  stale_tmp_cli.py VOLVIS OUTDIR

Writers name their temporaries "<OUT>.tmp-<host>-<pid>-<start>-<random>"
(src/core/tmpfiles.c). Checks, each against a real `volvis convert`:

- OME-Zarr (a temporary folder): a writer killed (SIGKILL) while its
  temporary store holds chunks leaves it; a second writer stopped (SIGSTOP)
  mid-write is still running. The next convert of the same OUT removes
  the killed writer's folder, keeps the stopped writer's, keeps a
  temporary faked for a live process (a `sleep` this test starts) and a
  name that does not parse, removes one faked for that live process's id
  with another start time (the id reused since), and writes a store equal,
  file for file and byte for byte, to one written without interruption.
  Once the stopped writer and the sleep are gone, the convert after
  removes theirs too.
- .vvb (a temporary file): killed mid-write, then written again: the
  temporary is gone and the file equals the uninterrupted one.
- NRRD through an atomic file (an unnamed O_TMPFILE, named only at the
  end): a faked temporary of a gone writer is removed, one of a live
  writer (this test) kept.
"""
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import time

VOLVIS, OUT = sys.argv[1], sys.argv[2]
shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def temp_re(base):
    return re.compile(re.escape(base) + r"\.tmp-([0-9a-f]{8})-([0-9]+)-([0-9]+)-([0-9a-f]{6})$")


def start_time(pid):
    """Field 22 of /proc/PID/stat (after the command name in parentheses)."""
    with open(f"/proc/{pid}/stat") as f:
        return int(f.read().rsplit(")", 1)[1].split()[19])


def holds_data(path):
    if os.path.isdir(path) and not os.path.islink(path):
        return any(files for _, _, files in os.walk(path))
    return os.path.isfile(path) and os.path.getsize(path) > 0


def tree(path):
    """{relative path: bytes} of every file under PATH."""
    out = {}
    for root, _, files in os.walk(path):
        for n in files:
            p = os.path.join(root, n)
            with open(p, "rb") as f:
                out[os.path.relpath(p, path)] = f.read()
    return out


def same(a, b):
    if os.path.isdir(a):
        return os.path.isdir(b) and tree(a) == tree(b)
    with open(a, "rb") as fa, open(b, "rb") as fb:
        return fa.read() == fb.read()


def convert(src, raw, out):
    return subprocess.run([VOLVIS, "convert", "--raw", raw, src, out, "-q"], capture_output=True,
                          text=True)


def caught_mid_write(out, sig):
    """Starts convert SRC OUT and sends SIG once its temporary beside OUT
    holds data; returns (process, temporary's name). The input is made
    larger (and the reference written again) and the run started again
    when a writer finishes before it is caught (a fast machine)."""
    global RAW
    pattern = temp_re(os.path.basename(out))
    for attempt in range(3):
        proc = subprocess.Popen([VOLVIS, "convert", "--raw", RAW, SRC, out, "-q"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 300
        while proc.poll() is None and time.monotonic() < deadline:
            for name in os.listdir(os.path.dirname(out)):
                m = pattern.match(name)
                if m and int(m[2]) == proc.pid and holds_data(os.path.join(os.path.dirname(out),
                                                                           name)):
                    proc.send_signal(sig)
                    return proc, name
            time.sleep(0.002)
        proc.kill()
        proc.wait()
        print(f"note: the writer ended before it was caught (try {attempt + 1})")
        RAW = make_input(int(RAW.split("x")[2].split(":")[0]) * 2)
    sys.exit("FAIL: no writer could be caught mid-write")


def make_input(slices):
    """SRC: SLICES slices of 256 x 256 u16 noise (slow to compress, so
    writing takes a while), and the store written from it uninterrupted
    (REF); returns its --raw description."""
    rng = random.Random(89)
    with open(SRC, "wb") as f:
        for _ in range(slices):
            f.write(rng.randbytes(256 * 256 * 2))
    raw = f"256x256x{slices}:u16"
    shutil.rmtree(REF, ignore_errors=True)
    p = convert(SRC, raw, REF)
    check(p.returncode == 0, f"the reference store of {slices} slices ({p.stderr.strip()})")
    return raw


SRC = os.path.join(OUT, "noise.raw")
REF = os.path.join(OUT, "ref", "out.ome.zarr")  # the same name: the store's metadata holds it
os.makedirs(os.path.dirname(REF))
RAW = make_input(256)
sleeper = subprocess.Popen(["sleep", "600"])

# ---- OME-Zarr: a temporary folder -----------------------------------------------------------
TARGET = os.path.join(OUT, "out.ome.zarr")
base = os.path.basename(TARGET)
killed, killed_tmp = caught_mid_write(TARGET, signal.SIGKILL)
killed.wait()
killed_start = temp_re(base).match(killed_tmp)[3]
check(os.path.isdir(os.path.join(OUT, killed_tmp)) and not os.path.exists(TARGET),
      f"a writer killed mid-write leaves its temporary folder {killed_tmp}")
host = temp_re(base).match(killed_tmp)[1]
stopped, stopped_tmp = caught_mid_write(TARGET, signal.SIGSTOP)
live_fake = f"{base}.tmp-{host}-{sleeper.pid}-{start_time(sleeper.pid)}-aaaaaa"
reused_fake = f"{base}.tmp-{host}-{sleeper.pid}-{start_time(sleeper.pid) + 1}-bbbbbb"
odd = f"{base}.tmp-not-a-writer"
os.makedirs(os.path.join(OUT, live_fake, "0"))
with open(os.path.join(OUT, live_fake, "0", "chunk"), "wb") as f:
    f.write(b"live")
os.makedirs(os.path.join(OUT, reused_fake))
with open(os.path.join(OUT, odd), "wb") as f:
    f.write(b"odd")

p = convert(SRC, RAW, TARGET)
left = set(os.listdir(OUT))
check(p.returncode == 0 and same(TARGET, REF),
      f"the next convert writes OUT whole, equal to the uninterrupted store ({p.stderr.strip()})")
check(killed_tmp not in left, "... and removes the killed writer's temporary folder")
check(stopped_tmp in left and holds_data(os.path.join(OUT, stopped_tmp)),
      "... keeps the temporary of a writer still running (stopped mid-write)")
check(live_fake in left, "... keeps a temporary named for a live process (sleep)")
check(reused_fake not in left, "... removes one of that process id with another start time")
check(odd in left, "... keeps a name that does not parse")

stopped.kill()
stopped.wait()
sleeper.kill()
sleeper.wait()
p = convert(SRC, RAW, TARGET)
left = set(os.listdir(OUT))
check(p.returncode == 0 and same(TARGET, REF) and stopped_tmp not in left
      and live_fake not in left and odd in left,
      "once those writers are gone, the convert after removes their temporaries: "
      f"{sorted(n for n in left if '.tmp-' in n)}")

# ---- .vvb: a temporary file -----------------------------------------------------------------
VREF = os.path.join(OUT, "ref.vvb")
p = convert(SRC, RAW, VREF)
check(p.returncode == 0, f"the reference .vvb is written ({p.stderr.strip()})")
VTARGET = os.path.join(OUT, "out.vvb")
vkilled, vtmp = caught_mid_write(VTARGET, signal.SIGKILL)
vkilled.wait()
check(os.path.isfile(os.path.join(OUT, vtmp)), f"a .vvb writer killed mid-write leaves {vtmp}")
p = convert(SRC, RAW, VTARGET)
check(p.returncode == 0 and same(VTARGET, VREF) and vtmp not in os.listdir(OUT),
      f"the next .vvb convert removes it and writes the whole file ({p.stderr.strip()})")

# ---- an atomic file (NRRD): named temporaries faked beside it -------------------------------
NTARGET = os.path.join(OUT, "out.nrrd")
nbase = os.path.basename(NTARGET)
gone = f"{nbase}.tmp-{host}-{killed.pid}-{killed_start}-cccccc"
mine = f"{nbase}.tmp-{host}-{os.getpid()}-{start_time(os.getpid())}-dddddd"
for n in (gone, mine):
    with open(os.path.join(OUT, n), "wb") as f:
        f.write(b"half")
p = convert(SRC, RAW, NTARGET)
left = set(os.listdir(OUT))
with open(NTARGET, "rb") as f:
    magic = f.read(4)
check(p.returncode == 0 and gone not in left and mine in left and magic == b"NRRD",
      f"an atomic file's writer removes a gone writer's temporary, keeps a live one's "
      f"({p.stderr.strip()})")

if not failures:  # the inputs and outputs are large: keep them only to look into a failure
    shutil.rmtree(OUT, ignore_errors=True)
print(f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
