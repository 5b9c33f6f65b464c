"""The fatigue node's ``done`` names its folder (a string): accepted, while a recorder-style
``files`` map of non-strings is still rejected (cosim/control.py)."""

from __future__ import annotations

import pytest

from cosim.control import check_node_control
from cosim.wire import WireError


def test_fatigue_done_with_its_folder_is_accepted() -> None:
    check_node_control("done", {"rejected": 0, "files": "/runs/x/fatigue", "max_damage": 1e-5,
                                "critical_node_id": 3})


@pytest.mark.parametrize("files", [{"csv": 3}, 5, ["a"]])
def test_done_files_neither_folder_nor_map_of_strings_is_rejected(files) -> None:
    with pytest.raises(WireError, match="files"):
        check_node_control("done", {"rejected": 0, "files": files})
