"""Zip an FMU staging directory (modelDescription.xml, binaries/...) into a reproducible .fmu."""

import os
import sys
import zipfile
from pathlib import Path

# Fixed timestamps and modes: the same inputs give a byte-identical .fmu.
EPOCH = (1980, 1, 1, 0, 0, 0)


def package(stage_dir, fmu_path):
    stage, fmu = Path(stage_dir), Path(fmu_path)
    files = sorted(path for path in stage.rglob("*") if path.is_file())
    if not (stage / "modelDescription.xml").is_file():
        raise SystemExit(f"{stage}: no modelDescription.xml to package")
    partial = fmu.with_name(fmu.name + ".partial")
    with zipfile.ZipFile(partial, "w") as archive:
        for path in files:
            info = zipfile.ZipInfo(path.relative_to(stage).as_posix(), date_time=EPOCH)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = (0o755 if path.suffix == ".so" else 0o644) << 16
            archive.writestr(info, path.read_bytes())
    # Renamed into place so an interrupted build never leaves a truncated .fmu behind.
    os.replace(partial, fmu)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit("usage: package.py STAGE_DIR OUT.fmu")
    package(sys.argv[1], sys.argv[2])
