"""The link's fixed-point resolutions (LSBs), read from the `fixed` line of the wire schema in
msg/src/messages.rs (`SCHEMA`, which the schema hash covers): fields such as the IMU, the
attitude and the velocity cross the UART as i16 counts of these, so a value comes back within
half a count."""
import os

_SCHEMA_RS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "msg", "src", "messages.rs")


def _read():
    with open(_SCHEMA_RS, encoding="utf-8") as f:
        for line in f:
            if line.startswith("fixed "):
                return {k: float(v) for k, v in (kv.split("=") for kv in line.split()[1:])}
    raise RuntimeError(f"no `fixed` line in {_SCHEMA_RS}")


LSB = _read()
