"""ROSS's noise-free phasors of a machine's `sweep` case next to its pointwise ones.

Usage:
  python3 scripts/ross_sweep_pointwise.py [--machine NAME] OUT.csv

For every logged speed of the machine's grid and every bearing and channel
(rel_y, rel_z, ped_y, ped_z): the steady-state phasor ROSS gives at that
speed (`pointwise`) and the phasor its tracking filter gives in the `sweep`
case (`averaged`: the mean over the speeds its block of revolutions spans,
scripts/ross_unseen.py `swept`), both without noise [m]; the block's speed
span [Hz] (a*N/f, `sweep_speeds`). The check of Plinth's averaging model
(host/src/estimate/sweep.rs) on an independent path:
tests/tests/sweep_averaging.rs. Needs ROSS 2.3.0 (as ross_unseen.py).
"""
import os
import sys
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ross_unseen as ru  # noqa: E402


def main(argv):
    machine = "unseen-seven"
    if len(argv) >= 2 and argv[0] == "--machine":
        machine, argv = argv[1], argv[2:]
    if len(argv) != 1:
        sys.exit(__doc__)
    m = ru.MACHINES[machine]
    sweep = next(e[1] for e in m["effects"]["sweep"] if e[0] == "sweep")
    with open(ru.machine_file(machine), "rb") as f:
        spec = tomllib.load(f)
    speeds = list(ru.speeds_of("sweep", 1, machine))
    point, _ = ru.respond(spec, speeds, [])
    avg, _ = ru.swept(spec, speeds, [], sweep)
    a, n = sweep["rate_hz_per_s"], sweep["revolutions"]
    with open(argv[0], "w") as out:
        out.write("speed_hz,bearing,channel,span_hz,pointwise_re,pointwise_im,averaged_re,averaged_im\n")
        for b in sorted(point):
            for c in ru.CHANNELS:
                for j, f in enumerate(speeds):
                    p, q = point[b][c][j], avg[b][c][j]
                    out.write(f"{f:.6g},{b},{c},{a * n / f:.6g},{p.real:.9e},{p.imag:.9e},{q.real:.9e},{q.imag:.9e}\n")


if __name__ == "__main__":
    main(sys.argv[1:])
