"""The sweep cache trusts nothing it finds (cosim.engine.sweep.bundle): a file laid out or kept
there is used only when its SHA-256 is the one the sweep shipped, and the cache folder itself is
refused when it is not this user's private folder."""

from __future__ import annotations

import os

import pytest

from cosim.engine.errors import InputError
from cosim.engine.cache import CacheError, cache_dir
from cosim.engine.sweep.bundle import Bundle, digest


@pytest.fixture
def shipped(tmp_path):
    """A scene and the table it reads, as a sweep ships them."""
    (tmp_path / "user").mkdir()
    scene, table = tmp_path / "user" / "scene.toml", tmp_path / "user" / "motion.csv"
    scene.write_text('[scene]\nduration = 1.0\n[trajectory]\ntable = "motion.csv"\n')
    table.write_text("time,z\n0,0\n1,0.1\n")
    return Bundle.of(scene, [table])


def test_files_planted_under_a_blobs_or_a_bundles_name_are_replaced(tmp_path, monkeypatch, shipped):
    bundle, blobs = shipped
    monkeypatch.setenv("COSIM_CACHE_DIR", str(tmp_path / "cache"))
    cache = cache_dir()
    for relative, expected in bundle.files:
        for place in (cache / "blobs" / expected, cache / "bundles" / bundle.key / relative):
            place.parent.mkdir(parents=True, exist_ok=True)
            place.write_text("someone else's file")
    elsewhere = tmp_path / "elsewhere.toml"
    elsewhere.write_text("[scene]\nduration = 99.0\n")
    linked = cache / "bundles" / bundle.key / "motion.csv"
    linked.unlink()
    linked.symlink_to(elsewhere)  # a link to a file of the right content would not do either
    target = bundle.place(blobs)
    assert target.read_bytes() == blobs[bundle.files[0][1]]
    for relative, expected in bundle.files:
        for place in (cache / "blobs" / expected, cache / "bundles" / bundle.key / relative):
            assert not place.is_symlink() and digest(place.read_bytes()) == expected, place
    assert elsewhere.read_text() == "[scene]\nduration = 99.0\n"  # replaced the link, not what it pointed at


def test_a_blob_damaged_on_its_way_is_refused(tmp_path, monkeypatch, shipped):
    bundle, blobs = shipped
    monkeypatch.setenv("COSIM_CACHE_DIR", str(tmp_path / "cache"))
    damaged = {key: value + b"!" if key == bundle.files[0][1] else value for key, value in blobs.items()}
    with pytest.raises(CacheError, match="arrived damaged"):
        bundle.place(damaged)


def test_a_new_cache_is_private_and_one_others_may_write_to_is_refused(tmp_path, monkeypatch):
    monkeypatch.setenv("COSIM_CACHE_DIR", str(tmp_path / "cache"))
    assert cache_dir().stat().st_mode & 0o077 == 0
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    monkeypatch.setenv("COSIM_CACHE_DIR", str(shared))
    with pytest.raises(CacheError, match="may be written by others") as refused:
        cache_dir()
    assert isinstance(refused.value, InputError) and "\n" not in str(refused.value)
    link = tmp_path / "link"
    link.symlink_to(tmp_path / "cache")
    monkeypatch.setenv("COSIM_CACHE_DIR", str(link))
    with pytest.raises(CacheError, match="not a folder of its own"):
        cache_dir()


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0, reason="giving a folder to another user needs root")
def test_a_cache_that_belongs_to_another_user_is_refused(tmp_path, monkeypatch):
    theirs = tmp_path / "theirs"
    theirs.mkdir(mode=0o700)
    os.chown(theirs, 65534, 65534)  # nobody
    monkeypatch.setenv("COSIM_CACHE_DIR", str(theirs))
    with pytest.raises(CacheError, match="belongs to another user"):
        cache_dir()


def test_the_default_cache_is_the_users_own_not_the_shared_temporary_folder(monkeypatch):
    import tempfile
    monkeypatch.delenv("COSIM_CACHE_DIR", raising=False)
    from cosim.engine import cache
    assert not str(cache._user_cache()).startswith(tempfile.gettempdir())
