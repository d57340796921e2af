"""Short TypeErrors for calls that match no signature of a compiled function: pybind11's own
message lists the signatures and the repr of every argument (hundreds of lines for arrays); this
one names the argument at fault, from the function's signature (the first line of its __doc__)."""
import functools
import re
from typing import Any, Callable, Dict, List, Optional, Tuple

Param = Tuple[str, str, bool]  # name, type, has a default


def split_top(text: str) -> List[str]:
    """text split at the commas outside brackets and quotes."""
    parts, depth, quote, start = [], 0, "", 0
    for k, c in enumerate(text):
        if quote:
            quote = "" if c == quote else quote
        elif c in "'\"":
            quote = c
        elif c in "([{":
            depth += 1
        elif c in ")]}":
            depth -= 1
        elif c == "," and depth == 0:
            parts.append(text[start:k].strip())
            start = k + 1
    if text[start:].strip():
        parts.append(text[start:].strip())
    return parts


def signature(fn: Any) -> Optional[Tuple[List[Param], List[Param], bool]]:
    """(positional parameters, keyword-only ones, takes **kwargs) of fn's first signature."""
    doc = (getattr(fn, "__doc__", None) or "").split("\n", 1)[0]
    m = re.match(r"\w+\((.*)\)( -> .*)?$", doc)
    if not m:
        return None
    positional: List[Param] = []
    keyword: List[Param] = []
    kwargs = False
    target = positional
    for part in split_top(m.group(1)):
        if part in ("*", "/") or part.startswith("*") and not part.startswith("**"):
            target = keyword if part != "/" else target
            continue
        if part.startswith("**"):
            kwargs = True
            continue
        name, _, rest = part.partition(":")
        target.append((name.strip(), rest.split(" = ")[0].strip(), " = " in rest))
    return positional, keyword, kwargs


def accepts(kind: str, value: Any) -> bool:
    """Whether pybind11 would convert value to the plain type named kind (other types: True)."""
    optional = re.fullmatch(r"Optional\[(\w+)\]", kind)
    if optional:
        return value is None or accepts(optional.group(1), value)
    if kind == "str":
        return isinstance(value, str)
    if kind == "bool":
        return type(value).__name__ in ("bool", "bool_")
    if kind == "int":
        return hasattr(value, "__index__") and not isinstance(value, bool)
    if kind == "float":
        return hasattr(value, "__float__") and not isinstance(value, (str, bytes))
    return True


def described(kind: str) -> str:
    """A pybind11 type name in words: Optional[float] -> a number or None."""
    optional = re.fullmatch(r"Optional\[(\w+)\]", kind)
    if optional:
        return described(optional.group(1)) + " or None"
    return {"str": "a string", "bool": "True or False", "int": "an integer", "float": "a number"}.get(kind, kind)


def explain(fn: Any, name: str, args: Tuple[Any, ...], kwargs: Dict[str, Any], method: bool) -> str:
    """Why the call name(*args, **kwargs) matches no signature, in a line."""
    sig = signature(fn)
    if sig is None:
        return f"{name}(): arguments of the wrong type"
    positional, keyword, takes_kwargs = sig
    given = list(args)
    if method:  # self is not the caller's business
        positional, given = positional[1:], given[1:]
    names = [p[0] for p in positional]
    if len(given) > len(positional):
        takes = f"{name}() takes {len(positional)} positional argument{'s' if len(positional) != 1 else ''}"
        given_text = f"{len(given)} {'was' if len(given) == 1 else 'were'} given"
        if not keyword:
            return f"{takes} ({', '.join(names)}) but {given_text}"
        return f"{takes} ({', '.join(names)}) but {given_text}; name the others: " + \
            ", ".join(p[0] + "=" for p in keyword)
    params = {p[0]: p for p in positional + keyword}
    for key in kwargs:
        if key not in params and not takes_kwargs:
            return f"{name}() got an unexpected keyword argument '{key}' (it takes {', '.join(params)})"
        if key in names[:len(given)]:
            return f"{name}() got {key} twice, by position and by keyword"
    bound = dict(zip(names, given), **kwargs)
    for param, kind, has_default in positional + keyword:
        if param not in bound:
            if not has_default:
                return f"{name}() is missing the argument {param}"
        elif not accepts(kind, bound[param]):
            return f"{name}(): {param} must be {described(kind)}, got {type(bound[param]).__name__}"
    return f"{name}(): arguments of the wrong type ({', '.join(params)})"


PYBIND11_MISMATCH = re.compile(r"incompatible (function|constructor) arguments")


def shortened(fn: Callable[..., Any], name: str, method: bool) -> Callable[..., Any]:
    @functools.wraps(fn)
    def call(*args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except TypeError as e:
            if not PYBIND11_MISMATCH.search(str(e)):
                raise
            raise TypeError(explain(fn, name, args, kwargs, method)) from None
    return call


def shorten_type_errors(module: Any) -> None:
    """Every function of the compiled module, and every method of its classes, raising short
    TypeErrors."""
    for attr, value in list(vars(module).items()):
        if isinstance(value, type):
            for key, member in list(vars(value).items()):
                if key.startswith("__") and key != "__init__":
                    continue
                shown = value.__name__ if key == "__init__" else f"{value.__name__}.{key}"
                if isinstance(member, staticmethod):
                    setattr(value, key, staticmethod(shortened(member.__func__, shown, False)))
                elif type(member).__name__ == "instancemethod":
                    setattr(value, key, shortened(getattr(value, key), shown, True))
        elif type(value).__name__ == "builtin_function_or_method":
            setattr(module, attr, shortened(value, attr, False))
