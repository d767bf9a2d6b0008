"""What the subcommands share (ursim_core.cli.common): the first-run notice, progress bars, staged output folders."""

from __future__ import annotations

from cli_helpers import run_python, two_rooms

from ursim_core.cli import main
from ursim_core.cli.common import progress_bar, staged_folder
from ursim_core.io import atomic


def test_first_run_says_the_kernels_are_compiling(tmp_path, monkeypatch, capsys):
    import ursim_core.cli.common as common
    from ursim_core.segmentation.maoris import kernel_cache

    monkeypatch.setattr(common, "_announced", False)
    monkeypatch.setattr(kernel_cache, "kernels_cached", lambda: False)
    rooms = two_rooms(tmp_path / "rooms.png")
    assert main(["segment", str(rooms), str(rooms), "--preset", "default", "-o", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    # Once per process, before the first segmentation.
    assert err.count("Compiling the segmentation kernels (first run only") == 1


def test_progress_bar_off_a_terminal_is_silent_and_does_not_import_tqdm(capsys):
    update = progress_bar(3, "segment")  # pytest's captured stderr is not a terminal
    update(1, text="a.png")
    update(2, 5)
    update.close()
    assert capsys.readouterr().err == ""
    code = "import json, sys; from ursim_core.cli.common import progress_bar; progress_bar(2, 'x')(2); print(json.dumps('tqdm' in sys.modules))"
    assert run_python(code) is False


def test_staged_outputs_sync_their_final_folder_once(tmp_path, directory_syncs):
    synced = directory_syncs
    out = tmp_path / "out"
    with staged_folder(out) as staging:
        for name in ("a.png", "b.png", "c.json"):
            atomic.atomic_write_bytes(staging / name, name.encode())
    assert synced == [str(out)]
    assert sorted(path.name for path in tmp_path.iterdir()) == ["out"]
    assert sorted(path.name for path in out.iterdir()) == ["a.png", "b.png", "c.json"]
