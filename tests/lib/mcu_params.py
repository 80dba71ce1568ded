"""The MCU parameters' firmware defaults for the peers, read from launch_configs/mcu_params.yaml
(generated from the one parameter table, msg/src/params.rs; a Rust test fails while it is
stale), so a peer never copies a default by hand. Plain Python (no YAML module in every venv):
the file's layout is the generator's, two levels of keys under `ros__parameters`."""
import os
import re

PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "launch_configs", "mcu_params.yaml")


def default(name):
    """`default("limits.max_tilt_deg")` → 45.0."""
    section, key = name.split(".", 1)
    with open(PATH, encoding="utf-8") as f:
        text = f.read()
    block = re.search(rf"^    {re.escape(section)}:\n((?:      .*\n)+)", text, re.M)
    m = block and re.search(rf"^      {re.escape(key)}: ([-0-9.eE+]+)$", block.group(1), re.M)
    if not m:
        raise KeyError(f"{PATH}: no {name}")
    return float(m.group(1))
