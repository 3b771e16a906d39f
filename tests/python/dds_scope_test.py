"""tests/support/dds_scope.py, the Python tests' topic scope on the shared DDS domain: the domain
is dds_scope.h's, the scope is one transport/topic_scope.h accepts (its alphabet and length) and
names the running test and process, names cut alike stay apart, and outside a test it is refused.
Run from ctest (python_dds_scope) with RTHS_SOURCE_DIR set."""
import os
import re
import sys
from pathlib import Path

import pytest

SOURCE = Path(os.environ["RTHS_SOURCE_DIR"])
sys.path.insert(0, str(SOURCE / "tests" / "support"))
import dds_scope  # noqa: E402


def header_constant(path, name):
    """The integer a C++ header gives `name` (`... name = N;`)."""
    found = re.search(rf"\b{name}\s*=\s*(\d+)", (SOURCE / path).read_text())
    assert found, f"{path} defines no {name}"
    return int(found.group(1))


def test_the_domain_is_the_one_the_cpp_tests_share():
    assert dds_scope.SHARED_DOMAIN == header_constant("tests/support/dds_scope.h", "kSharedDomain")


def test_the_scope_names_this_test_and_process_in_the_alphabet_topics_accept(monkeypatch):
    monkeypatch.delenv(dds_scope.SCOPE_VARIABLE, raising=False)
    assert dds_scope.scope_dds_to_this_test(monkeypatch) == dds_scope.SHARED_DOMAIN
    scope = os.environ[dds_scope.SCOPE_VARIABLE]
    assert re.fullmatch(r"[A-Za-z0-9_]+", scope), scope
    assert len(scope) <= header_constant("transport/topic_scope.h", "kMaxScopeLength"), scope
    assert scope.startswith("dds_scope_test_test_the_scope_names_this_test"), scope
    assert scope.endswith(f"_{os.getpid()}"), scope


def test_names_cut_alike_and_pids_stay_apart():
    stem = "x" * 80
    first, second = dds_scope.dds_scope_for(stem + "a", 1), dds_scope.dds_scope_for(stem + "b", 1)
    assert first[:60] == second[:60] and first != second
    assert dds_scope.dds_scope_for("one.test", 1) != dds_scope.dds_scope_for("one.test", 2)
    assert re.fullmatch(r"[A-Za-z0-9_]+", dds_scope.dds_scope_for("ü test/ü:1", 7))


def test_outside_a_test_it_is_refused_naming_why(monkeypatch):
    monkeypatch.delenv("PYTEST_CURRENT_TEST")
    with pytest.raises(RuntimeError, match="PYTEST_CURRENT_TEST"):
        dds_scope.scope_dds_to_this_test(monkeypatch)


def test_the_scope_is_restored_when_the_test_ends(monkeypatch):
    with monkeypatch.context() as this_test:
        this_test.setenv(dds_scope.SCOPE_VARIABLE, "the_scope_before")
        with monkeypatch.context() as inner_test:
            dds_scope.scope_dds_to_this_test(inner_test)
            assert os.environ[dds_scope.SCOPE_VARIABLE] != "the_scope_before"
        assert os.environ[dds_scope.SCOPE_VARIABLE] == "the_scope_before"
