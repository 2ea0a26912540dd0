"""The type stubs against the module as built: every difference, listed.

binbow/__init__.pyi and binbow/distributed.pyi (read from the source tree,
not the build's copies) must name what binbow and binbow.distributed export,
with each class's methods, static and class methods, properties (read-only or
not) and attributes, and each function's and method's parameters: names,
order, kinds (positional-only, keyword-only, *args, **kwargs), which have a
default, and the default's value when both sides spell it as a literal.
Annotations are not compared: pybind11 spells types its own way.

The stubs are parsed with ast (no mypy or stubtest). Python callables are read
with inspect.signature; pybind11 ones from the signature pybind11 writes at the
top of __doc__ ("Overloaded function." and one numbered line per overload,
which the stub gives as @overload variants, matched as sets). pybind11's
unnamed arguments (arg0, ...) cannot be passed by keyword: the stub must make
them positional-only. A **kwargs of the module may be spelled in the stub as
the keyword-only parameters it accepts, each named in the docstring.
"""
import ast
import importlib
import inspect
import re
from collections import namedtuple
from pathlib import Path

import pytest

import binbow

STUBS = Path(__file__).resolve().parents[1] / "binbow"
MODULES = {"binbow": STUBS / "__init__.pyi", "binbow.distributed": STUBS / "distributed.pyi"}

Parameter = inspect.Parameter
POSITIONAL_ONLY = Parameter.POSITIONAL_ONLY
POSITIONAL_OR_KEYWORD = Parameter.POSITIONAL_OR_KEYWORD
VAR_POSITIONAL = Parameter.VAR_POSITIONAL
KEYWORD_ONLY = Parameter.KEYWORD_ONLY
VAR_KEYWORD = Parameter.VAR_KEYWORD

# A parameter: name, kind (inspect's), default (NO_DEFAULT, UNKNOWN or the value).
Param = namedtuple("Param", "name kind default")
NO_DEFAULT = Parameter.empty


class _Unknown:
    def __repr__(self):
        return "..."


UNKNOWN = _Unknown()  # a default that is not a literal (or the stub's `= ...`)

# Names neither side needs to declare: set by Python itself, or inherited from
# object and left out of stubs by convention.
MODULE_IGNORED = {"__all__", "__builtins__", "__cached__", "__doc__", "__file__", "__loader__",
                  "__name__", "__package__", "__path__", "__spec__"}
CLASS_IGNORED = {"__annotations__", "__dict__", "__doc__", "__firstlineno__", "__hash__",
                 "__init_subclass__", "__module__", "__orig_bases__", "__parameters__",
                 "__qualname__", "__repr__", "__slots__", "__static_attributes__", "__str__",
                 "__weakref__",
                 # copyreg caches it on a class once an instance is pickled (other tests do).
                 "__slotnames__"}


def is_dunder(name):
    return len(name) > 4 and name.startswith("__") and name.endswith("__")


def is_public(name, ignored):
    return (not name.startswith("_") or is_dunder(name)) and name not in ignored


# --- pybind11 signatures, from __doc__ ------------------------------------------------------

def closing_parenthesis(text, start):
    """The index of the ')' closing the '(' at text[start], outside quotes and brackets."""
    depth, quote, i = 0, None, start
    while i < len(text):
        c = text[i]
        if quote:
            if c == "\\":
                i += 1
            elif c == quote:
                quote = None
        elif c in "'\"":
            quote = c
        elif c in "([{<":
            depth += 1
        elif c in ")]}>":
            depth -= 1
            if depth == 0:
                return i
        i += 1
    raise ValueError(f"unbalanced signature: {text[start:]!r}")


def split_top_level(text, separator):
    """text split at `separator` characters outside quotes and brackets."""
    parts, depth, quote, current, i = [], 0, None, [], 0
    while i < len(text):
        c = text[i]
        if quote:
            if c == "\\" and i + 1 < len(text):
                current.append(c)
                i += 1
                c = text[i]
            elif c == quote:
                quote = None
        elif c in "'\"":
            quote = c
        elif c in "([{<":
            depth += 1
        elif c in ")]}>":
            depth -= 1
        elif c == separator and depth == 0:
            parts.append("".join(current))
            current = []
            i += 1
            continue
        current.append(c)
        i += 1
    parts.append("".join(current))
    return parts


def literal(text):
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
        return UNKNOWN


def parse_pybind_parameters(text):
    """The parameters of a pybind11 signature's parenthesised list (without the parentheses)."""
    params, kind = [], POSITIONAL_OR_KEYWORD
    for piece in split_top_level(text, ","):
        piece = piece.strip()
        if not piece:
            continue
        if piece == "/":
            params = [p._replace(kind=POSITIONAL_ONLY) for p in params]
        elif piece == "*":
            kind = KEYWORD_ONLY
        elif piece.startswith("**"):
            params.append(Param(piece[2:].split(":")[0].strip(), VAR_KEYWORD, NO_DEFAULT))
        elif piece.startswith("*"):
            params.append(Param(piece[1:].split(":")[0].strip(), VAR_POSITIONAL, NO_DEFAULT))
            kind = KEYWORD_ONLY
        else:
            head, *default = split_top_level(piece, "=")
            name = head.split(":")[0].strip()
            value = literal("=".join(default).strip()) if default else NO_DEFAULT
            # pybind11 calls an argument without py::arg "argN": no keyword reaches it.
            this_kind = POSITIONAL_ONLY if re.fullmatch(r"arg\d+", name) else kind
            params.append(Param(name, this_kind, value))
    return params


def pybind_signatures(name, doc):
    """The parameter lists of a pybind11 function `name`, one per overload; None when
    its __doc__ does not start with pybind11's signature."""
    doc = doc or ""
    if re.match(rf"{re.escape(name)}\(\*args, \*\*kwargs\)\n\s*Overloaded function\.", doc):
        starts = [m.end() - 1 for m in
                  re.finditer(rf"^\s*\d+\. {re.escape(name)}\(", doc, re.MULTILINE)]
    elif doc.startswith(name + "("):
        starts = [len(name)]
    else:
        return None
    return [parse_pybind_parameters(doc[start + 1:closing_parenthesis(doc, start)])
            for start in starts] or None


# --- Python callables, with inspect --------------------------------------------------------

def python_parameters(function):
    params = []
    for p in inspect.signature(function).parameters.values():
        if p.default is Parameter.empty:
            default = NO_DEFAULT
        else:
            default = p.default if literal(repr(p.default)) is not UNKNOWN else UNKNOWN
        params.append(Param(p.name, p.kind, default))
    return params


def runtime_signatures(function, name, bound):
    """The parameter lists of a module's callable (without self or cls when `bound`),
    one per overload; None when they cannot be read."""
    if inspect.isfunction(function):
        signatures = [python_parameters(function)]
    else:
        signatures = pybind_signatures(name, getattr(function, "__doc__", None))
        if signatures is None:
            return None
    return [s[1:] if bound else s for s in signatures]


# --- the stubs ------------------------------------------------------------------------------

def stub_parameters(node, bound):
    """The parameters of a stub's def (without self or cls when `bound`)."""
    arguments = node.args
    params = []
    positional = arguments.posonlyargs + arguments.args
    first_default = len(positional) - len(arguments.defaults)
    for index, argument in enumerate(positional):
        if index >= first_default:
            default = literal(arguments.defaults[index - first_default])
            if default is Ellipsis:
                default = UNKNOWN
        else:
            default = NO_DEFAULT
        # The older spelling of positional-only: a name with two leading underscores.
        old_style = argument.arg.startswith("__") and not argument.arg.endswith("__")
        kind = (POSITIONAL_ONLY if index < len(arguments.posonlyargs) or old_style
                else POSITIONAL_OR_KEYWORD)
        params.append(Param(argument.arg, kind, default))
    if arguments.vararg:
        params.append(Param(arguments.vararg.arg, VAR_POSITIONAL, NO_DEFAULT))
    for argument, value in zip(arguments.kwonlyargs, arguments.kw_defaults):
        default = NO_DEFAULT if value is None else literal(value)
        if default is Ellipsis:
            default = UNKNOWN
        params.append(Param(argument.arg, KEYWORD_ONLY, default))
    if arguments.kwarg:
        params.append(Param(arguments.kwarg.arg, VAR_KEYWORD, NO_DEFAULT))
    return params[1:] if bound else params


def decorator_name(node):
    if isinstance(node, ast.Call):
        node = node.func
    if isinstance(node, ast.Attribute):
        return node.attr
    return node.id if isinstance(node, ast.Name) else ""


class StubMember:
    """A name a stub declares: its kind ("class", "function", "method", "staticmethod",
    "classmethod", "property", "attribute" or "re-export") and its AST node(s)."""

    def __init__(self, kind, nodes):
        self.kind, self.nodes = kind, nodes


def stub_body(body, in_class):
    """The public names a stub's module or class body declares."""
    members = {}
    ignored = CLASS_IGNORED if in_class else MODULE_IGNORED

    def add(name, kind, node):
        if is_public(name, ignored):
            members[name] = StubMember(kind, [node])

    for node in body:
        if isinstance(node, ast.If):  # sys.version_info branches: both count
            members.update(stub_body(node.body + node.orelse, in_class))
        elif isinstance(node, ast.ClassDef):
            add(node.name, "class", node)
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            decorators = [decorator_name(d) for d in node.decorator_list]
            if "setter" in decorators or "deleter" in decorators:
                if node.name in members and members[node.name].kind == "property":
                    members[node.name].kind = "writable property"
                continue
            if "overload" in decorators and node.name in members:
                members[node.name].nodes.append(node)
                continue
            kind = "method" if in_class else "function"
            for special in ("staticmethod", "classmethod", "property"):
                if special in decorators:
                    kind = special
            add(node.name, kind, node)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            add(node.target.id, "attribute", node)
        elif isinstance(node, ast.Assign):
            for target in node.targets:
                if isinstance(target, ast.Name):
                    add(target.id, "attribute", node)
        elif isinstance(node, (ast.Import, ast.ImportFrom)) and not in_class:
            for alias in node.names:  # only `import x as x` re-exports in a stub
                if alias.asname is not None and alias.asname == alias.name.split(".")[-1]:
                    add(alias.asname, "re-export", node)
    return members


# --- the module as built --------------------------------------------------------------------

def runtime_exports(module):
    """The public names of a module: __all__, public names it defines (classes and
    functions of its own or of its private submodules, constants), and dunders
    such as __version__."""
    names = set(getattr(module, "__all__", ()))
    for name, value in vars(module).items():
        if not is_public(name, MODULE_IGNORED) or inspect.ismodule(value):
            continue
        if inspect.isclass(value) or callable(value):
            owner = getattr(value, "__module__", None) or ""
            if owner != module.__name__ and not owner.startswith(module.__name__ + "._"):
                continue  # imported from elsewhere, not exported here
        names.add(name)
    return names


def runtime_kind(value, in_class):
    if isinstance(value, type):
        return "class"
    if isinstance(value, staticmethod):
        return "staticmethod"
    if isinstance(value, classmethod):
        return "classmethod"
    if isinstance(value, property):
        return "property" if value.fset is None else "writable property"
    if callable(value):
        return "method" if in_class else "function"
    return "attribute"


def instance_attributes(cls):
    """Public attributes a Python class's methods assign to self (self.x = ...)."""
    if not any(inspect.isfunction(v) for v in vars(cls).values()):
        return set()  # a compiled class, or one without methods
    try:
        tree = ast.parse(inspect.getsource(cls).strip())
    except (OSError, TypeError, SyntaxError):
        return set()
    names = set()
    for node in ast.walk(tree):
        targets = []
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, (ast.AnnAssign, ast.AugAssign)):
            targets = [node.target]
        for target in targets:
            for item in ast.walk(target):
                if (isinstance(item, ast.Attribute) and isinstance(item.value, ast.Name)
                        and item.value.id == "self" and not item.attr.startswith("_")):
                    names.add(item.attr)
    return names


def runtime_members(cls):
    """name: (kind, value) of what a class defines itself (inherited members are its
    bases' business). A slot wrapper __init__ is pybind11's "no constructor"."""
    members = {}
    for name, value in vars(cls).items():
        if not is_public(name, CLASS_IGNORED) or type(value).__name__ == "wrapper_descriptor":
            continue
        members[name] = (runtime_kind(value, in_class=True), value)
    for name in instance_attributes(cls) - set(members):
        members[name] = ("attribute", None)
    return members


# --- comparing ------------------------------------------------------------------------------

def render(params):
    """A parameter list as Python would spell it, without annotations."""
    out = []
    star = any(p.kind is VAR_POSITIONAL for p in params)
    for index, p in enumerate(params):
        if p.kind is KEYWORD_ONLY and not star:
            out.append("*")
            star = True
        text = {VAR_POSITIONAL: "*", VAR_KEYWORD: "**"}.get(p.kind, "") + p.name
        if p.default is not NO_DEFAULT:
            text += "=" + repr(p.default)
        out.append(text)
        following = params[index + 1] if index + 1 < len(params) else None
        if p.kind is POSITIONAL_ONLY and getattr(following, "kind", None) is not POSITIONAL_ONLY:
            out.append("/")
    return "(" + ", ".join(out) + ")"


KIND_NAMES = {POSITIONAL_ONLY: "positional-only", POSITIONAL_OR_KEYWORD: "positional-or-keyword",
              VAR_POSITIONAL: "*args", KEYWORD_ONLY: "keyword-only", VAR_KEYWORD: "**kwargs"}


def describe(default):
    return "none" if default is NO_DEFAULT else repr(default)


def same_default(a, b):
    if (a is NO_DEFAULT) != (b is NO_DEFAULT):
        return False
    if UNKNOWN in (a, b) or a is NO_DEFAULT:
        return True
    numbers = (int, float)
    if (isinstance(a, numbers) and isinstance(b, numbers)
            and not isinstance(a, bool) and not isinstance(b, bool)):
        return a == b or (a != a and b != b)
    return type(a) is type(b) and a == b


def same_parameter(a, b):
    if a.kind is not b.kind:
        return False
    # Names that no caller can use need not agree.
    if a.kind not in (POSITIONAL_ONLY, VAR_POSITIONAL, VAR_KEYWORD) and a.name != b.name:
        return False
    return same_default(a.default, b.default)


def parameter_differences(module, stub, doc):
    """Why a stub's parameter list differs from the module's ([] when it does not)."""
    reasons = []
    if any(p.kind is VAR_KEYWORD for p in module) and not any(p.kind is VAR_KEYWORD for p in stub):
        names = {p.name for p in module}
        spelled = [p for p in stub if p.kind is KEYWORD_ONLY and p.name not in names]
        if spelled:  # the keywords the module's **kwargs takes
            for p in spelled:
                if not re.search(rf"\b{re.escape(p.name)}\b", doc or ""):
                    reasons.append(f"keyword {p.name!r} stands for the module's **kwargs, "
                                   "but its docstring does not name it")
            module = [p for p in module if p.kind is not VAR_KEYWORD]
            stub = [p for p in stub if p not in spelled]
    for index in range(max(len(module), len(stub))):
        ours = module[index] if index < len(module) else None
        theirs = stub[index] if index < len(stub) else None
        if ours is not None and theirs is not None and same_parameter(ours, theirs):
            continue
        where = f"parameter {index + 1}"
        if ours is None or theirs is None:
            reasons.append(f"{where}: only in the {'stub' if ours is None else 'module'}")
        elif ours.kind is not theirs.kind:
            reasons.append(f"{where}: {KIND_NAMES[ours.kind]} in the module, "
                           f"{KIND_NAMES[theirs.kind]} in the stub")
        elif not same_parameter(ours._replace(default=theirs.default), theirs):
            reasons.append(f"{where}: {ours.name!r} in the module, {theirs.name!r} in the stub")
        else:
            reasons.append(f"{where} {ours.name!r}: default {describe(ours.default)} in the "
                           f"module, {describe(theirs.default)} in the stub")
        break  # what follows a difference is rarely worth reading
    return reasons


def signature_differences(qualname, module_signatures, stub_nodes, bound, doc):
    """Differences between a callable's overloads and its stub's, matched as sets."""
    if module_signatures is None:
        return [f"{qualname}: cannot read the module's signature (no pybind11 signature at "
                "the top of __doc__)"]
    stubs = [stub_parameters(node, bound) for node in stub_nodes]
    if len(module_signatures) == 1 and len(stubs) == 1:
        reasons = parameter_differences(module_signatures[0], stubs[0], doc)
        if reasons:
            return [f"{qualname}: parameters differ: module {render(module_signatures[0])}, "
                    f"stub {render(stubs[0])}: " + "; ".join(reasons)]
        return []
    problems = []
    unmatched = list(stubs)
    for signature in module_signatures:
        match = next((s for s in unmatched if not parameter_differences(signature, s, doc)), None)
        if match is None:
            problems.append(f"{qualname}: the module's overload {render(signature)} has no "
                            "matching @overload in the stub")
        else:
            unmatched.remove(match)
    problems += [f"{qualname}: the stub's @overload {render(s)} matches no overload of the "
                 "module" for s in unmatched]
    return problems


def compatible(module_kind, stub_kind):
    # A read-write property and an attribute are used alike.
    return module_kind == stub_kind or (module_kind, stub_kind) == ("writable property",
                                                                    "attribute")


def base_names(cls):
    return [b.__name__ for b in cls.__bases__
            if b is not object and b.__module__ != "pybind11_builtins"]


def stub_base_names(node):
    names = []
    for base in node.bases:
        while isinstance(base, ast.Subscript):  # list[LoopResult]
            base = base.value
        names.append(decorator_name(base))
    return [n for n in names if n != "object"]


def class_differences(qualname, cls, node):
    problems = []
    if base_names(cls) != stub_base_names(node):
        problems.append(f"{qualname}: bases differ: module {base_names(cls)}, stub "
                        f"{stub_base_names(node)}")
    members = runtime_members(cls)
    stubbed = stub_body(node.body, in_class=True)
    for name in sorted(set(members) - set(stubbed)):
        problems.append(f"{qualname}.{name}: the module's {members[name][0]} has no stub")
    for name in sorted(set(stubbed) - set(members)):
        problems.append(f"{qualname}.{name}: the stub's {stubbed[name].kind} is not in the "
                        "module")
    for name in sorted(set(members) & set(stubbed)):
        (kind, value), stub = members[name], stubbed[name]
        where = f"{qualname}.{name}"
        if not compatible(kind, stub.kind):
            problems.append(f"{where}: a {kind} in the module, a {stub.kind} in the stub")
        elif kind == "class":
            problems += class_differences(where, value, stub.nodes[0])
        elif kind in ("method", "staticmethod", "classmethod"):
            function = value.__func__ if kind != "method" else value
            bound = kind != "staticmethod"
            doc = "\n".join(filter(None, [getattr(function, "__doc__", None), cls.__doc__]))
            problems += signature_differences(where, runtime_signatures(function, name, bound),
                                              stub.nodes, bound, doc)
    return problems


def module_differences(module, stub_text):
    """Every difference between a module and its stub's text, one line each."""
    stubbed = stub_body(ast.parse(stub_text).body, in_class=False)
    exported = runtime_exports(module)
    problems = []
    for name in sorted(exported - set(stubbed)):
        if not hasattr(module, name):
            problems.append(f"{module.__name__}.{name}: in __all__ but not in the module")
        else:
            kind = runtime_kind(getattr(module, name), in_class=False)
            problems.append(f"{module.__name__}.{name}: the module's {kind} has no stub")
    for name in sorted(set(stubbed) - exported):
        problems.append(f"{module.__name__}.{name}: the stub's {stubbed[name].kind} is not "
                        "exported by the module")
    for name in sorted(exported & set(stubbed)):
        if not hasattr(module, name):
            continue
        value, stub, where = getattr(module, name), stubbed[name], f"{module.__name__}.{name}"
        kind = runtime_kind(value, in_class=False)
        if stub.kind == "re-export":
            continue
        if kind != stub.kind:
            problems.append(f"{where}: a {kind} in the module, a {stub.kind} in the stub")
        elif kind == "class":
            problems += class_differences(where, value, stub.nodes[0])
        elif kind == "function":
            problems += signature_differences(
                where, runtime_signatures(value, name, bound=False), stub.nodes, False,
                getattr(value, "__doc__", None))
    return problems


# --- the tests ------------------------------------------------------------------------------

@pytest.mark.parametrize("name", sorted(MODULES))
def test_the_stubs_match_the_module(name):
    module = importlib.import_module(name)
    stub = MODULES[name]
    problems = module_differences(module, stub.read_text(encoding="utf-8"))
    assert not problems, (f"{stub} does not match {module.__file__} "
                          f"({len(problems)} differences):\n  " + "\n  ".join(problems))


def test_pybind11_signatures_are_parsed():
    doc = ("f(self: m.C, a: int, b: Dict[str, int] = {'x': 1, 'y': 2}, arg2: str = 'a,b)',"
           " /, c: float = 1.5, *args, d: object = <m.D object at 0x1>, **kwargs) -> None\n\n"
           "Docs.\n")
    assert render(pybind_signatures("f", doc)[0]) == (
        "(self, a, b={'x': 1, 'y': 2}, arg2='a,b)', /, c=1.5, *args, d=..., **kwargs)")
    assert render(pybind_signatures("g", "g(arg0: int, x: int = 2, *, y: int) -> int")[0]) \
        == "(arg0, /, x=2, *, y)"
    overloaded = ("h(*args, **kwargs)\nOverloaded function.\n\n"
                  "1. h(self: m.C, x: int) -> None\n\nOne.\n\n"
                  "2. h(self: m.C, x: str, y: int = 0) -> None\n\nTwo: h(x) again.\n")
    assert [render(s) for s in pybind_signatures("h", overloaded)] == ["(self, x)",
                                                                       "(self, x, y=0)"]
    assert pybind_signatures("k", "Something else.") is None


def test_overloads_are_matched_as_sets():
    def stub(text):
        return [node for node in ast.parse(text).body if isinstance(node, ast.FunctionDef)]

    module = pybind_signatures("h", "h(*args, **kwargs)\nOverloaded function.\n\n"
                                    "1. h(x: int) -> None\n\n2. h(x: str, y: int = 0) -> None\n")
    both = stub("@overload\ndef h(x: str, y: int = 0) -> None: ...\n"
                "@overload\ndef h(x: int) -> None: ...\n")
    assert signature_differences("m.h", module, both, False, "") == []
    one = stub("def h(x: int) -> None: ...\n")
    assert signature_differences("m.h", module, one, False, "") == [
        "m.h: the module's overload (x, y=0) has no matching @overload in the stub"]
    wrong = stub("@overload\ndef h(x: int) -> None: ...\n"
                 "@overload\ndef h(x: str, z: int = 0) -> None: ...\n")
    assert signature_differences("m.h", module, wrong, False, "") == [
        "m.h: the module's overload (x, y=0) has no matching @overload in the stub",
        "m.h: the stub's @overload (x, z=0) matches no overload of the module"]


def test_every_kind_of_difference_is_reported():
    """The real stub, edited: each edit must show up (the check is not vacuous)."""
    text = MODULES["binbow"].read_text(encoding="utf-8")
    edits = [
        ("def hamming(", "def hammings("),  # a function renamed
        ("        max_results: int = 10,\n", "        max_result: int = 10,\n"),  # a parameter
        ("def add(self, descriptors: _Descriptors, label: Optional[str] = None)",
         "def add(self, descriptors: _Descriptors, label: Optional[str])"),  # a default dropped
        ("seed: int = 0,\n        threads", "seed: int = 1,\n        threads"),  # a default changed
        ("    def clear(self) -> None: ...\n    def feature_vector",
         "    def feature_vector"),  # a method gone
        ("    @property\n    def nodes(self)", "    def nodes(self)"),  # a property as a method
        ("    frequency: float\n", "    @property\n    def frequency(self) -> float: ...\n"),
        ("    *,\n    max_features", "    max_features"),  # keyword-only no more
        ("        new_word_distance: float = ...,\n", "        new_word_distanse: float = ...,\n"),
    ]
    for old, new in edits:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    text += "class Bogus: ...\n"
    problems = "\n".join(module_differences(binbow, text))
    for expected in [
        "binbow.hamming: the module's function has no stub",
        "binbow.hammings: the stub's function is not exported by the module",
        "binbow.Database.query: parameters differ",
        "stub (image, max_result=10",
        "parameter 2: 'max_results' in the module, 'max_result' in the stub",
        "binbow.Vocabulary.build: parameters differ: module (images, branching=10, levels=6, "
        "weighting='tf-idf', scoring='l1', seed=0,",
        "parameter 6 'seed': default 0 in the module, 1 in the stub",
        "binbow.Database.add: parameters differ: module (descriptors, label=None), stub "
        "(descriptors, label): parameter 2 'label': default None in the module, none in the stub",
        "binbow.Database.clear: the module's method has no stub",
        "binbow.BuildProgress.nodes: a property in the module, a method in the stub",
        "binbow.LoopDetectorParams.frequency: a writable property in the module, a property in "
        "the stub",
        "binbow.detect_loops: parameters differ",
        "parameter 6: keyword-only in the module, positional-or-keyword in the stub",
        "keyword 'new_word_distanse' stands for the module's **kwargs, but its docstring does "
        "not name it",
        "binbow.Bogus: the stub's class is not exported by the module",
    ]:
        assert expected in problems, f"{expected!r} not in:\n{problems}"
