"""Plan.save and Plan.load on hostile paths: save replaces regular files
only (never a device, FIFO, folder or symbolic link, never through a link
planted at a temporary name), load reads at most 16 MiB."""
import os
import stat

import pytest

import triquint


def test_save_refuses_what_is_not_a_regular_file(case1, tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with pytest.raises(OSError, match="FIFO"):
        case1.save(fifo)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    target = tmp_path / "target"
    target.write_text("keep")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    with pytest.raises(OSError, match="symbolic link"):
        case1.save(link)
    assert link.is_symlink() and target.read_text() == "keep"
    with pytest.raises(OSError, match="folder"):
        case1.save(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo", "link.json", "target"]


def test_save_as_root_leaves_a_device_node_alone(case1, tmp_path):
    if os.geteuid() != 0:
        pytest.skip("mknod needs root (CI runs as root)")
    dev = tmp_path / "full"
    os.mknod(dev, 0o666 | stat.S_IFCHR, os.makedev(1, 7))  # a /dev/full
    with pytest.raises(OSError, match="device"):
        case1.save(dev)
    assert stat.S_ISCHR(os.lstat(dev).st_mode)


def test_save_ignores_links_at_the_old_temporary_names(case1, tmp_path):
    target = tmp_path / "target"
    target.write_text("keep")
    out = tmp_path / "plan.json"
    pid = os.getpid()
    for name in [f".plan.json.{pid}.tmp", f".plan.json.tmp{pid}"]:
        (tmp_path / name).symlink_to(target)
    case1.save(out)
    assert target.read_text() == "keep"
    assert triquint.Plan.load(out) == case1


def test_load_stops_at_its_limit():
    with pytest.raises(OSError, match="larger than 16 MiB"):
        triquint.Plan.load("/dev/zero")
