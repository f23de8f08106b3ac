"""The belt drive, which first writes the PLANTHUB_TLS_* entries of its environment as JSON to the file
its first argument names (what the hub handed it), then serves as usual with the rest."""
import json
import os
import sys

from hub.participant import serve
from modules.belt_drive_logic import BeltDrive

if __name__ == "__main__":
    with open(sys.argv[1], "w", encoding="utf-8") as out:
        json.dump({k: v for k, v in os.environ.items() if k.startswith("PLANTHUB_TLS_")}, out)
    raise SystemExit(serve(BeltDrive(), sys.argv[2:]))
