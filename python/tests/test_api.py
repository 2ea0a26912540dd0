"""The package's surface: version, docstrings on everything (the stubs: test_stubs.py)."""
import inspect
import re

import binbow
from conftest import SOURCE_DIR


def test_version_is_the_project_version():
    assert binbow.__version__ == (SOURCE_DIR / "VERSION").read_text(encoding="utf-8").strip()


def public_members():
    """(qualified name, object) of every public function, class, method and property."""
    for name in binbow.__all__:
        value = getattr(binbow, name)
        yield name, value
        if inspect.isclass(value) and not issubclass(value, BaseException):
            for member, attribute in vars(value).items():
                if member.startswith("__") and member not in {
                    "__init__", "__len__", "__eq__", "__contains__", "__repr__", "__copy__",
                    "__deepcopy__",
                }:
                    continue
                if member.startswith("_") and not member.startswith("__"):
                    continue
                if not callable(attribute) and not inspect.isdatadescriptor(attribute):
                    continue  # plain data, described by its class's docstring
                yield f"{name}.{member}", attribute


def own_doc(name, value):
    """The docstring minus pybind11's signature lines."""
    doc = inspect.getdoc(value) or ""
    lines = [line for line in doc.splitlines()
             if not re.match(r"^(\d+\. )?\w*\(.*\)( -> .*)?$", line.strip())
             and line.strip() != "Overloaded function."]
    return "\n".join(lines).strip()


def test_every_function_method_and_property_has_a_docstring():
    missing = [name for name, value in public_members() if not own_doc(name, value)]
    assert not missing, f"without a docstring: {missing}"


def test_the_package_is_typed():
    assert (SOURCE_DIR / "python" / "binbow" / "py.typed").is_file()


def test_classes_are_named_after_the_package():
    for name in binbow.__all__:
        if not isinstance(getattr(binbow, name), type):
            continue
        assert getattr(binbow, name).__module__ == "binbow"
    assert "binbow.Vocabulary" in binbow.Database.__init__.__doc__
