"""Probe 2 cases for --out: hostile targets, two commands on one --out at
once, --force over another command's output, hostile bearing names.
"""
import os
import shutil

from probe_inputs_common import *  # noqa: F401,F403


# --- --out and concurrency
def some_writer(d, out):
    which = rng.choice(["simulate", "import", "plot", "report", "signals", "extract"])
    if which == "simulate":
        return which, ["simulate", MACHINE, "--speeds", "5:60:5", "--out", out]
    if which == "signals":
        return which, ["signals", MACHINE, "--rundown", "60:55:5", "--out", out]
    if which == "import":
        i = d + "/in-import"
        if not os.path.isdir(i):
            shutil.copytree(F, i)
        return which, ["import", i + "/vector-table.csv", "--layout", i + "/layout.toml",
                       "--bearings", i + "/bearings.csv", "--out", out, "--plots"]
    if which == "extract":
        i = d + "/in-extract"
        if not os.path.isdir(i):
            shutil.copytree(F, i)
        return which, ["extract", i + "/recording.wav", "--channels", i + "/channels.toml",
                       "--bearings", i + "/bearings.csv", "--out", out]
    r = d + "/run"
    if not os.path.isdir(r):
        shutil.copytree(W + "/base-run", r)
    return which, [which, r, "--out", out]


@builder
def out_hostile(d):
    style = rng.choice(["existing-file", "input-file", "inside-input-dir", "parent-of-inputs", "empty-string",
                        "trailing-slash", "deep-new", "dev-null", "read-only-parent", "out-dotdot-into-input"])
    out = d + "/out"
    exp = "error"
    os.mkdir(d + "/in")
    open(d + "/in/precious.txt", "w").write("do not lose me\n")
    if style == "existing-file":
        open(out, "w").write("precious\n")
    elif style == "inside-input-dir":
        exp = "any"
    elif style == "empty-string":
        out = ""
    elif style == "trailing-slash":
        exp = "any"
    elif style == "deep-new":
        out = d + "/a/b/c/out"
        exp = "any"
    elif style == "dev-null":
        out = "/dev/null"
    elif style == "read-only-parent":
        os.mkdir(d + "/ro")
        os.chmod(d + "/ro", 0o555)
        out = d + "/ro/out"
        if os.geteuid() == 0:
            exp = "any"  # root writes into a read-only directory
    which, argv = some_writer(d, out if style not in ("trailing-slash", "inside-input-dir") else "PLACEHOLDER")
    if style == "input-file":
        inputs = [a for a in argv if os.path.isfile(a)]
        out = inputs[0] if inputs else d + "/in/precious.txt"
    elif style == "inside-input-dir":
        inputs = [a for a in argv[1:] if os.path.exists(a) and a.startswith(d)]
        base = os.path.dirname(inputs[0]) if inputs and os.path.isfile(inputs[0]) else (inputs[0] if inputs else d + "/in")
        out = base + "/results"
    elif style == "parent-of-inputs":
        out = d
    elif style == "trailing-slash":
        out = d + "/out/"
    elif style == "out-dotdot-into-input":
        inputs = [a for a in argv[1:] if os.path.exists(a) and a.startswith(d)]
        out = (os.path.dirname(inputs[0]) if inputs and os.path.isfile(inputs[0]) else d + "/in") + "/../out/.."
    argv = [out if a == "PLACEHOLDER" or a == argv[argv.index("--out") + 1] else a for a in argv]
    return {"argv": argv, "out": out if style in ("inside-input-dir", "trailing-slash", "deep-new", "read-only-parent") else d + "/none",
            "expect": exp, "command": which, "what": f"--out {style}", "chmod_back": d + "/ro"}


@builder
def out_concurrent(d):
    out = d + "/out"
    if rng.random() < 0.5:
        os.mkdir(out)  # the user made it empty beforehand
    w1, a1 = some_writer(d, out)
    w2, a2 = some_writer(d, out)
    return {"argv": a1, "second": a2, "out": d + "/none", "shared_out": out, "expect": "any",
            "command": f"{w1}+{w2}", "what": f"{w1} and {w2} at once into one --out"}


@builder
def out_force_over_other(d):
    """--force onto a run another command wrote: the other files kept?"""
    out = d + "/out"
    w1, a1 = some_writer(d, out)
    p = run(a1)
    if p.returncode != 0:
        return {"argv": a1, "out": d + "/none", "expect": "any", "command": w1, "what": "(setup failed)"}
    open(out + "/my-notes.txt", "w").write("mine\n")
    w2, a2 = some_writer(d, out)
    # --force replaces what Plinth wrote there: only the user's file is guarded.
    return {"argv": a2 + ["--force"], "out": out, "out_replaced": True,
            "keep_in_out": out + "/my-notes.txt",
            "expect": "any", "command": f"{w2} --force", "what": f"{w2} --force over {w1}'s run + a user file"}


@builder
def names_hostile(d):
    """Names from tables that reach file names (not the first probe's ../../x)."""
    c, r = identify_case(d, "error", rng.choice(["plot", "report", "identify"]))
    name = rng.choice(["CON", "a\u202eb", "left\u00a0", "x" * 65, "..", ".hidden", "left\tA", "名前", "lpt1",
                       "a*b", "a?b", "~", "-rf"])
    for fn in ("measurements.csv", "bearings.csv"):
        rows = csv_rows(r + "/" + fn)
        for x in rows[1:]:
            if x[1] == "left":
                x[1] = name
        write_rows(r + "/" + fn, rows)
    # A trailing no-break space is trimmed like any space (the same name in
    # both files); the others are letters a file system takes.
    if name in ("名前", "CON", "lpt1", "~", "-rf", "left\u00a0"):
        c["expect"] = "any"
    if c["command"] == "identify":
        c["argv"] += ["--plots", d + "/out"]
    c["what"] = f"bearing named {name!r}"
    return c
