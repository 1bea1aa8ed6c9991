"""Decodes frames with canmatrix (an independent DBC decoder) for the protocol tests.

usage: /usr/bin/python3 canmatrix_decode.py DBC FRAMES
FRAMES: one frame a line, "<id hex> <payload hex>". Prints one JSON object a line:
{"name": frame name, "fd": whether the DBC makes it a CAN FD frame, "raw": {signal: int},
"phys": {signal: "decimal string"}}, or
{"error": "..."} for a frame the DBC does not know.
"""
import json
import sys
import warnings

warnings.filterwarnings("ignore")
import canmatrix  # noqa: E402
import canmatrix.formats  # noqa: E402


def main():
    db = canmatrix.formats.loadp_flat(sys.argv[1])
    with open(sys.argv[2]) as frames:
        for line in frames:
            ident, payload = line.split()
            frame = db.frame_by_id(canmatrix.ArbitrationId(id=int(ident, 16), extended=False))
            if frame is None:
                print(json.dumps({"error": "unknown id " + ident}))
                continue
            decoded = frame.decode(bytes.fromhex(payload))
            print(json.dumps({
                "name": frame.name,
                "fd": bool(frame.is_fd),
                "raw": {k: int(v.raw_value) for k, v in decoded.items()},
                "phys": {k: str(v.phys_value) for k, v in decoded.items()},
            }))


if __name__ == "__main__":
    main()
