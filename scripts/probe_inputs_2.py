"""The cases of scripts/probe-inputs-2.sh (read its header).

Each builder makes one case in its own directory from clean copies of the
bundled examples and returns what to run and what the case expects. Cases
go round the builders (every builder runs at least once when CASES is at
least their number), each drawing its variant from the seeded generator.

The builders live by command family in probe_inputs_2_*.py, imported here
in a fixed order (the order decides which builder each case number gets);
the baselines and helpers every case starts from are in
probe_inputs_common.py, the runner and classifier in probe_inputs_runner.py.
"""
import probe_inputs_2_import  # noqa: F401
import probe_inputs_2_rundir  # noqa: F401
import probe_inputs_2_options  # noqa: F401
import probe_inputs_2_extract  # noqa: F401
import probe_inputs_2_out  # noqa: F401
from probe_inputs_common import B
from probe_inputs_runner import main

main(B)
