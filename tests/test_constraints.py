"""``constraints.txt`` (the versions the suite last passed with, which the README's two
commands and ``.ci/run`` install) pins every dependency ``pyproject.toml`` names, the test
and cluster extras' too, at a version inside its range: a dependency added or a range
moved without the file renewed is caught here, not by a fresh machine's install."""

import tomllib
from pathlib import Path

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name
from packaging.version import Version

ROOT = Path(__file__).resolve().parents[1]


def pins() -> dict[str, Version]:
    """The constraints file's ``name==version`` lines, by canonical name."""
    lines = (ROOT / "constraints.txt").read_text().splitlines()
    requirements = [Requirement(line) for line in lines if line.strip() and not line.startswith("#")]
    assert all(len(r.specifier) == 1 and next(iter(r.specifier)).operator == "==" for r in requirements)
    return {canonicalize_name(r.name): Version(next(iter(r.specifier)).version) for r in requirements}


def test_every_dependency_is_pinned_within_its_range():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    extras = project["optional-dependencies"]
    pinned = pins()
    for requirement in map(Requirement, project["dependencies"] + extras["test"] + extras["cluster"]):
        version = pinned.get(canonicalize_name(requirement.name))
        assert version is not None, f"{requirement.name} is not in constraints.txt"
        assert requirement.specifier.contains(version, prereleases=True), f"{requirement} against {version}"


def test_ci_and_the_readme_install_with_the_constraints():
    assert "-c constraints.txt -e '.[test,cluster]'" in (ROOT / ".ci" / "run").read_text()
    readme = (ROOT / "README.md").read_text()
    assert "pip install -c constraints.txt -e '.[test,cluster]' && python -m pytest" in readme
    assert "pip install -c constraints.txt -e . && flashsync demo" in readme
