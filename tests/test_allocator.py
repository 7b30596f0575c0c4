import ctypes
import os
import subprocess
import sys

import pytest

from blueprint import allocator


class _Libc:
    def __init__(self) -> None:
        self.calls: list[tuple[int, int]] = []

    def mallopt(self, param: int, value: int) -> int:
        self.calls.append((param, value))
        return 1


@pytest.fixture
def libc(monkeypatch):
    fake = _Libc()
    monkeypatch.setattr(ctypes, "CDLL", lambda name: fake)
    for name in allocator.USER_SETTINGS:
        monkeypatch.delenv(name, raising=False)
    return fake


def test_the_command_keeps_freed_memory_for_its_next_arrays(libc):
    allocator.keep_freed()
    # mmap threshold, top pad and trim threshold (malloc.h's M_* numbers)
    assert dict(libc.calls) == {
        -3: allocator.MMAP_THRESHOLD,
        -2: allocator.TOP_PAD,
        -1: allocator.TRIM_THRESHOLD,
    }


@pytest.mark.parametrize("name", allocator.USER_SETTINGS)
def test_a_users_own_allocator_settings_are_left_as_they_are(libc, monkeypatch, name):
    monkeypatch.setenv(name, "1")
    allocator.keep_freed()
    assert libc.calls == []


def test_one_arena_sets_the_arena_count(libc):
    allocator.one_arena()
    assert libc.calls == [(-8, 1)]


def test_without_glibc_nothing_is_set(monkeypatch):
    def missing(name):
        raise OSError(name)

    monkeypatch.setattr(ctypes, "CDLL", missing)
    allocator.keep_freed()
    allocator.one_arena()
    # a C library without glibc's mallopt
    monkeypatch.setattr(ctypes, "CDLL", lambda name: object())
    allocator.keep_freed()
    allocator.one_arena()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
def test_the_real_allocator_takes_the_settings():
    # mallopt answers 0 for a value it refuses: the thresholds must be within glibc's bounds
    code = (
        "import ctypes; from blueprint import allocator as a; libc = ctypes.CDLL('libc.so.6');"
        "wanted = ((-3, a.MMAP_THRESHOLD), (-2, a.TOP_PAD), (-1, a.TRIM_THRESHOLD));"
        "print([libc.mallopt(p, v) for p, v in wanted])"
    )
    env = {k: v for k, v in os.environ.items() if k not in allocator.USER_SETTINGS}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert out.stdout.strip() == "[1, 1, 1]"
