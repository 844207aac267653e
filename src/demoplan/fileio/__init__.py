"""Reading and writing demoplan's JSON/YAML files: format tags, units, atomic writes.

Every file carries ``"format": "demoplan/<kind>-<version>"`` (docs/formats.md). Files
are written atomically — to a temporary file in the target's folder, flushed
and renamed over the target — so a reader never sees half a file and a failed
write leaves the old one in place.

- :mod:`~demoplan.fileio.reading`: documents read and checked;
- :mod:`~demoplan.fileio.writing`: atomic writes, staged outputs, output targets;
- :mod:`~demoplan.fileio.folders`: a folder of outputs swapped in with a manifest;
- :mod:`~demoplan.fileio.paths`: file names and OS errors in words.
"""

from __future__ import annotations

from demoplan.fileio.folders import (
    MANIFEST,
    staged_folder,
)
from demoplan.fileio.paths import (
    display_path,
    os_error,
    os_reason,
)
from demoplan.fileio.reading import (
    FORMAT_VERSION,
    MAX_FILE_BYTES,
    MAX_YAML_BYTES,
    check_format,
    describe_validation_error,
    read_document,
    read_input_text,
    require_regular_file,
)
from demoplan.fileio.writing import (
    MAX_FILE_NAME_BYTES,
    UPDATE_WAIT_SECONDS,
    StagedOutputs,
    check_output_folder,
    dump_json,
    file_inside,
    locked_for_update,
    make_folders,
    output_target,
    refuse_overwriting_inputs,
    remove_made_folders,
    safe_file_name,
    write_atomic,
    write_atomic_bytes,
)

__all__ = [
    "FORMAT_VERSION",
    "MANIFEST",
    "MAX_FILE_BYTES",
    "MAX_FILE_NAME_BYTES",
    "MAX_YAML_BYTES",
    "UPDATE_WAIT_SECONDS",
    "StagedOutputs",
    "check_format",
    "check_output_folder",
    "describe_validation_error",
    "display_path",
    "dump_json",
    "file_inside",
    "locked_for_update",
    "make_folders",
    "os_error",
    "os_reason",
    "output_target",
    "read_document",
    "read_input_text",
    "refuse_overwriting_inputs",
    "remove_made_folders",
    "require_regular_file",
    "safe_file_name",
    "staged_folder",
    "write_atomic",
    "write_atomic_bytes",
]
