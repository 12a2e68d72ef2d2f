"""Component metadata files (MAVLink's component information protocol, JSON as its schemas
lay out): the general metadata naming the vehicle and the parameter metadata, generated from
the parameter definitions (emulator.flight.params), served over MAVLink FTP. The
COMPONENT_METADATA message that announces them is not in the pinned dialect, so a client
reads them at their FTP paths.
"""

from __future__ import annotations

import functools
import json
import zlib

from emulator.flight.params import PARAM_DEFINITIONS

__all__ = ["GENERAL_PATH", "PARAMETERS_PATH", "metadata_files"]

GENERAL_PATH = "/metadata/component_general.json"
PARAMETERS_PATH = "/metadata/parameters.json"
COMP_METADATA_TYPE_PARAMETER = 1


def _json(value: object) -> bytes:
    return json.dumps(value, indent=1, sort_keys=True).encode()


@functools.cache
def metadata_files() -> dict[str, bytes]:
    """FTP path -> file content."""
    parameters = _json({"version": 1, "parameters": [
        {"name": d.name, "type": "Int32" if d.is_int else "Float", "default": d.default,
         "min": d.minimum, "max": d.maximum, "shortDesc": d.description}
        for d in PARAM_DEFINITIONS]})
    general = _json({
        "version": 1, "vendorName": "mavswarm", "modelName": "PX4 SITL quadrotor (emulated)",
        "hardwareVersion": "SITL", "metadataTypes": [
            {"type": COMP_METADATA_TYPE_PARAMETER, "uri": f"mftp://{PARAMETERS_PATH}",
             "fileCrc": zlib.crc32(parameters)}],
    })
    return {GENERAL_PATH: general, PARAMETERS_PATH: parameters}
