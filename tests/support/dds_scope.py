"""One DDS domain for the Python tests that run processes over Cyclone DDS, each test on topics of
its own: the Python side of tests/support/dds_scope.h (transport/topic_scope.h reads the scope).

SHARED_DOMAIN: the domain those tests share (dds_scope.h's kSharedDomain).
dds_scope_for(name, pid) -> a topic scope for `name` (any text) in process `pid`: its ASCII letters
  and digits with '_' for anything else, cut to 60 characters, then the FNV-1a hash (32 bits) of
  the name's UTF-8 bytes and the pid, as dds_scope.h forms it.
scope_dds_to_this_test(monkeypatch) -> SHARED_DOMAIN, having set RTHS_DDS_SCOPE in this process's
  environment through the test's `monkeypatch` to the scope of the running pytest test ("<file
  stem>.<test>", from PYTEST_CURRENT_TEST, as a gtest name is "<suite>.<test>") and this process,
  so every process it starts from then on (`rths launch`, rths.Study.launch) names its topics by
  it; the variable is restored when the test ends (pytest runs a file's tests in one process, so a
  later test must not inherit this one's scope). Raises RuntimeError outside a test.
"""
import os

SHARED_DOMAIN = 10
SCOPE_VARIABLE = "RTHS_DDS_SCOPE"


def dds_scope_for(name, pid):
    kept = "".join(c if c.isascii() and c.isalnum() else "_" for c in name)[:60]
    digest = 2166136261
    for byte in name.encode("utf-8"):
        digest = ((digest ^ byte) * 16777619) & 0xFFFFFFFF
    return f"{kept}_{digest:08x}_{pid}"


def scope_dds_to_this_test(monkeypatch):
    current = os.environ.get("PYTEST_CURRENT_TEST")
    if not current:
        raise RuntimeError("scope_dds_to_this_test: no running pytest test (PYTEST_CURRENT_TEST "
                           "is unset); call it inside a test")
    path, _, test = current.rsplit(" (", 1)[0].partition("::")
    name = os.path.splitext(os.path.basename(path))[0] + "." + test
    monkeypatch.setenv(SCOPE_VARIABLE, dds_scope_for(name, os.getpid()))
    return SHARED_DOMAIN
