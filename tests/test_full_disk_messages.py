"""A full disk while writing a picture or a sweep's designs: one line naming the file and the cause,
even with -q (the disks are small tmpfs mounts, tests/conftest.py)."""

from __future__ import annotations

from pathlib import Path

from torus_cad.cli import main


def _fill(disk: Path) -> None:
    """Leave a few kB free on ``disk``."""
    with open(disk / "fill", "wb") as handle:
        try:
            while True:
                handle.write(b"\0" * 65536)
        except OSError:
            pass
    (disk / "fill").write_bytes((disk / "fill").read_bytes()[:-8192])


def test_a_picture_on_a_full_disk_is_one_line_naming_the_file(tmpfs, capsys, tmp_path) -> None:
    disk = tmpfs(512)
    _fill(disk)
    assert main(["preview", "--out", str(disk / "p.png")]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(disk / "p.png") in err and "No space left" in err
    assert "libpng" not in err and not (disk / "p.png").exists()


def test_a_quiet_sweep_on_a_full_disk_prints_why_it_failed(tmpfs, capsys, tmp_path) -> None:
    sweep = tmp_path / "one.toml"
    sweep.write_text(
        '[base.resolution]\nsections = 12\npoints = 32\n\n[sweep]\nmode = "grid"\n\n'
        "[vary]\nblades = [2]\n"
    )
    disk = tmpfs(512)
    _fill(disk)
    assert main(["sweep", str(sweep), "-q", "--workers", "1", "--out", str(disk / "sweep")]) == 1
    err = capsys.readouterr().err
    assert "no space left" in err.lower()
