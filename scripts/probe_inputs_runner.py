"""How a probe case is run and classified (the classes of
scripts/probe-inputs.sh's header), and the loop over the registered
builders that prints one count per class.
"""
import hashlib
import os
import re
import shutil
import signal
import subprocess
import threading

from probe_inputs_common import *  # noqa: F401,F403


def snapshot(d, exclude):
    seen = {}
    for root, dirs, files in os.walk(d):
        for f in files + dirs:
            p = os.path.join(root, f)
            if any(p == e or p.startswith(e.rstrip("/") + "/") for e in exclude):
                continue
            if os.path.islink(p):
                seen[p] = "link " + os.readlink(p)
            elif os.path.isfile(p):
                try:
                    seen[p] = hashlib.sha1(open(p, "rb").read()).hexdigest()
                except OSError:
                    seen[p] = "unreadable"
            elif os.path.isdir(p):
                seen[p] = "dir"
    return seen


def phasors(path):
    rows = csv_rows(path)
    out = {}
    for x in rows[1:]:
        out[(round(float(x[0]), 6), x[1])] = [float(v) for v in x[2:10]]
    return out


def compare(c, stdout):
    kind = c["compare"][0]
    if kind == "stdout":
        return stdout == c["compare"][1]
    produced = os.path.join(c["out"], c["compare"][1])
    if not os.path.isfile(produced):
        return False
    a, b = open(produced).read(), open(c["compare"][2]).read()
    if kind == "file":
        return a == b
    if kind == "sorted":
        return sorted(a.splitlines()) == sorted(b.splitlines())
    pa, pb = phasors(produced), phasors(c["compare"][2])
    if pa.keys() != pb.keys():
        return False
    for k in pa:
        scale = max(abs(v) for v in pb[k]) or 1.0
        if any(abs(x - y) > 1e-3 * scale for x, y in zip(pa[k], pb[k])):
            return False
    return True


def interrupted(argv, d, delay):
    """Runs `argv` in `d` and sends SIGINT after `delay` s (if still
    running): (exit code, stdout, stderr), code None if it then hangs."""
    p = subprocess.Popen([PLINTH, "--quiet"] + argv, cwd=d, stdin=subprocess.DEVNULL,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        o, e = p.communicate(timeout=delay)
    except subprocess.TimeoutExpired:
        p.send_signal(signal.SIGINT)
        try:
            o, e = p.communicate(timeout=LIMIT)
        except subprocess.TimeoutExpired:
            p.kill()
            p.communicate()
            return None, "", ""
    return p.returncode, o.decode("utf-8", "replace"), e.decode("utf-8", "replace")


def complete(c, atomic, now):
    """Whether the --out an interrupted command left (`now`, a snapshot)
    is the whole of what it writes uninterrupted (the signal came after
    the commit): the same files with the same tables and JSON."""
    if now is None:
        return False
    check = c["dir"] + "/out-check"
    argv = [check if a == atomic else a for a in c["argv"] if a != "--force"]
    p = run(argv, cwd=c["dir"], timeout=LIMIT)
    if p.returncode != 0:
        return False
    want = snapshot(check, [])
    shutil.rmtree(check, ignore_errors=True)
    rel = lambda s, root: {os.path.relpath(k, root): v for k, v in s.items()
                           if not os.path.basename(k).startswith(".")}
    a, b = rel(now, atomic), rel(want, check)
    if a.keys() != b.keys():
        return False
    return all(a[k] == b[k] for k in a if k.endswith((".csv", ".json")))


def after_interrupt(c, atomic, atomic_before, lost, new, err):
    """The class of a command stopped by SIGINT: the --out as it was (or
    still absent), nothing else changed, and what the interrupted command
    left beside --out cleared by the same command run again."""
    d = c["dir"]
    now = snapshot(atomic, []) if os.path.isdir(atomic) else None
    if lost:
        return "data-loss", "changed or removed: " + ", ".join(lost[:5]), err
    if now != atomic_before and not complete(c, atomic, now):
        if atomic_before is not None:
            return "data-loss", "the run under --out changed though the command was interrupted", err
        return "garbage", "an interrupted command left a partial --out", err
    if new:
        return "outside-out", "new: " + ", ".join(new[:5]), err
    left = sorted(f for f in os.listdir(d) if ".plinth-" in f)
    if left:
        p = run(c["argv"], cwd=d, timeout=LIMIT)
        still = sorted(f for f in os.listdir(d) if ".plinth-" in f)
        if still:
            return "outside-out", f"hidden copies left after SIGINT and a rerun (exit {p.returncode}): " + ", ".join(still[:3]), err
        return "ok", "leftovers of the interrupt cleared by the rerun: " + ", ".join(left[:3]), err
    return "ok", "", err


def classify(c):
    d = c["dir"]
    # A --out that does not exist yet is the command's to fill; one that
    # exists (a file, a user's directory) is guarded like any other file.
    excl = [o for o in (c["out"], c.get("shared_out"))
            if o and not os.path.lexists(o) or (o and os.path.isdir(o) and not os.listdir(o))]
    if c.get("out_replaced"):
        excl.append(c["out"])
    # An --out that must change all at once or not at all (interrupted
    # commands): guarded on its own below.
    atomic = c.get("atomic_out")
    if atomic:
        excl.append(atomic)
    atomic_before = snapshot(atomic, []) if atomic and os.path.isdir(atomic) else None
    excl = [o.rstrip("/") for o in excl]
    before = {p: h for p, h in snapshot(d, excl).items() if ".plinth-" not in p}
    shared = c.get("shared_out")
    keep = c.get("keep_in_out")
    keep_hash = hashlib.sha1(open(keep, "rb").read()).hexdigest() if keep else None
    results = [None, None]

    def one(k, argv):
        if k == 0 and "interrupt_after" in c:
            results[k] = interrupted(argv, d, c["interrupt_after"])
            return
        try:
            p = run(argv, env=c.get("env"), cwd=d, timeout=LIMIT)
            results[k] = (p.returncode, p.stdout.decode("utf-8", "replace"), p.stderr.decode("utf-8", "replace"))
        except subprocess.TimeoutExpired:
            results[k] = (None, "", "")

    threads = [threading.Thread(target=one, args=(0, c["argv"]))]
    if "second" in c:
        threads.append(threading.Thread(target=one, args=(1, c["second"])))
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    if os.path.isdir(c.get("chmod_back") or "/nonexistent"):
        os.chmod(c["chmod_back"], 0o755)
    code, out, err = results[0]
    after = snapshot(d, excl)
    lost = sorted(os.path.relpath(p, d) for p, h in before.items() if after.get(p) != h)
    new = sorted(os.path.relpath(p, d) for p in after if p not in before and ".plinth-" not in p
                 and not any(p.startswith(x) for x in [d + "/out", d + "/a", d + "/tmp"])
                 and not (shared and p.startswith(shared)))
    if keep and (not os.path.isfile(keep) or hashlib.sha1(open(keep, "rb").read()).hexdigest() != keep_hash):
        lost.append(os.path.relpath(keep, d))
    if "second" in c:
        c2, o2, e2 = results[1]
        if c2 is None:
            code = None
        elif code == 0 and c2 == 0 and not c.get("both_may_win"):
            lost.append("both writers exited 0 on one --out: " + "; ".join(sorted(os.listdir(shared)))[:200])
        elif code != 0 and c2 == 0:
            code, out, err = c2, o2, e2 + "\n(first) " + err
        elif code != 0 and c2 != 0:
            err = err + "\n(second) " + e2
        # The losing writer's message must name the --out.
        loser = e2 if c2 != 0 else (err if results[0][0] != 0 else "")
        if loser and shared not in loser and os.path.basename(shared) not in loser:
            err += "\n(loser does not name --out)"
    if code is None:
        return "hang", "", ""
    if atomic and code in (-signal.SIGINT, 128 + signal.SIGINT):
        return after_interrupt(c, atomic, atomic_before, lost, new, err)
    if lost:
        return "data-loss", "changed or removed: " + ", ".join(lost[:5]), err
    if new:
        return "outside-out", "new: " + ", ".join(new[:5]), err
    if "panicked" in err:
        return "panic", "", err
    if code < 0 or code >= 128:
        return "abort", f"exit {code}", err
    if code == 0:
        written = ""
        if c["out"] and os.path.isdir(c["out"]):
            for root, _, files in os.walk(c["out"]):
                for f in files:
                    if f.endswith((".csv", ".json")):
                        written += open(os.path.join(root, f), errors="replace").read()
        if re.search(r"(?<![A-Za-z_])(inf|NaN|nan)(?![A-Za-z_])", out + written):
            return "garbage", "inf/NaN in the output", err
        if c["expect"] == "error":
            return "garbage", "accepted (expected an error)", err
        judged = re.search(r'UNTRUSTED|NOT to be trusted|"trusted": ?false', out)
        if c["expect"] == "warn" and "warning" not in err and not judged:
            return "garbage", "accepted without a warning", err
        if c["expect"] == "neutral" and "compare" in c and not compare(c, out):
            return "garbage", "result differs from the clean input's", err
        return "ok", "", err
    last = [l for l in err.splitlines() if l.startswith("error:")]
    msg = last[-1] if last else err.strip()[-300:]
    if last and msg.rstrip().endswith(":"):  # clap lists what it means below
        msg = err.strip()[-300:]
    names_place = re.search(r"(\.csv|\.toml|\.wav|\.json|raw\.bin|--[a-z]|/)", msg)
    if c.get("names_line") and not re.search(r"line \d+|:\d+(:\d+)?:", msg):
        names_place = None
    if "(loser does not name --out)" in err:
        names_place = None
    return ("clear-error" if last and names_place else "unclear-error"), "", err


def main(builders):
    """Builds CASES cases round `builders`, runs and classifies each, prints
    the cases that are neither ok nor a clear error and the count per class."""
    cases = []
    for n in range(CASES):
        d = os.path.join(W, f"case{n:04d}")
        os.mkdir(d)
        b = builders[n % len(builders)]
        c = b(d)
        c["dir"] = d
        c["builder"] = b.__name__
        cases.append(c)

    counts, notes = {}, []
    log = open(os.path.join(W, "errors.txt"), "w")
    for c in cases:
        cls, why, err = classify(c)
        counts[cls] = counts.get(cls, 0) + 1
        lines = (err.strip().splitlines() or ["(no message)"])
        shown = [l for l in lines if l.startswith("error:")] or lines
        log.write(f"{cls:14} {c['command']:18} {c['what']}\n    {' '.join(c['argv'])[:400]}\n    {shown[-1][:400]}\n")
        if cls not in ("ok", "clear-error"):
            notes.append(f"{cls:14} {c['command']:18} {c['what']}: {why} | {shown[-1][:300]}")
        if "--classes" in os.environ.get("PROBE_FLAGS", ""):
            print(f"{cls:14} {c['command']:18} {c['what']}", flush=True)
    log.close()
    if os.environ.get("KEEP") == "1":
        print(f"every case's message: {W}/errors.txt")
    for n in notes:
        print(n)
    print(f"{len(cases)} cases ({len(builders)} builders, seed {SEED}):", ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
