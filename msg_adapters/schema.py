"""`ros2msg` schema text for a message class, built from the class itself.

MCAP's ros2 profile wants each channel's schema as the .msg text of the type
followed by the text of every type it depends on, each introduced by a line
of 80 `=` and `MSG: pkg/Type`. The Python wheels of ROS messages ship no .msg
files, so the text is rebuilt from the generated classes: field names and
types from `SLOT_TYPES`, constants from the class's constant table.
"""

import importlib

from rosidl_parser import definition as idl

SEPARATOR = "=" * 80

# IDL spellings of the primitive types back to their .msg spellings.
_MSG_PRIMITIVE = {
    "boolean": "bool",
    "octet": "byte",
    "char": "char",
    "wchar": "wchar",
    "float": "float32",
    "double": "float64",
    "long double": "float64",
    "short": "int16",
    "unsigned short": "uint16",
    "long": "int32",
    "unsigned long": "uint32",
    "long long": "int64",
    "unsigned long long": "uint64",
}


def message_class(type_name):
    """The generated class for 'pkg/msg/Type' or 'pkg/Type'."""
    parts = type_name.split("/")
    pkg, name = parts[0], parts[-1]
    interface = parts[1] if len(parts) == 3 else "msg"
    return getattr(importlib.import_module(f"{pkg}.{interface}"), name)


def type_name(msg_class):
    """'pkg/msg/Type', the name rosbag2 gives a channel's schema."""
    module = msg_class.__module__.split(".")
    return f"{module[0]}/{module[1]}/{msg_class.__name__}"


def _short_name(msg_class):
    module = msg_class.__module__.split(".")
    return f"{module[0]}/{msg_class.__name__}"


def _element_text(t):
    """.msg spelling of a non-array type, plus the class it refers to, if any."""
    if isinstance(t, idl.BasicType):
        return _MSG_PRIMITIVE.get(t.typename, t.typename), None
    if isinstance(t, idl.NamespacedType):
        cls = message_class("/".join([*t.namespaces, t.name]))
        return f"{t.namespaces[0]}/{t.name}", cls
    if isinstance(t, idl.BoundedString):
        return f"string<={t.maximum_size}", None
    if isinstance(t, idl.UnboundedString):
        return "string", None
    if isinstance(t, idl.BoundedWString):
        return f"wstring<={t.maximum_size}", None
    if isinstance(t, idl.UnboundedWString):
        return "wstring", None
    raise TypeError(f"no .msg spelling for {t!r}")


def _field_text(t):
    if isinstance(t, idl.Array):
        base, cls = _element_text(t.value_type)
        return f"{base}[{t.size}]", cls
    if isinstance(t, idl.BoundedSequence):
        base, cls = _element_text(t.value_type)
        return f"{base}[<={t.maximum_size}]", cls
    if isinstance(t, idl.UnboundedSequence):
        base, cls = _element_text(t.value_type)
        return f"{base}[]", cls
    return _element_text(t)


def _constants(msg_class):
    for key, value in vars(type(msg_class)).items():
        if key.endswith("__constants") and isinstance(value, dict):
            return value
    return {}


def _constant_line(name, value):
    # The generated classes keep constant values but not their declared types;
    # the type is inferred from the value. Constants never reach the wire, so
    # this choice cannot change how a message decodes.
    if isinstance(value, bytes) and len(value) == 1:
        return f"byte {name}={value[0]}"
    if isinstance(value, bool):
        return f"bool {name}={'true' if value else 'false'}"
    if isinstance(value, int):
        if -(2**31) <= value < 2**31:
            kind = "int32"
        elif value < 0 or value < 2**63:
            kind = "int64"
        else:
            kind = "uint64"
        return f"{kind} {name}={value}"
    if isinstance(value, float):
        return f"float64 {name}={value!r}"
    return f"string {name}={value}"


def definition_text(msg_class):
    """The .msg text of one type (constants, then fields), and the classes of
    the types its fields refer to, in field order."""
    lines = [_constant_line(k, v) for k, v in _constants(msg_class).items()]
    deps = []
    names = list(msg_class.get_fields_and_field_types())
    for field, slot_type in zip(names, msg_class.SLOT_TYPES):
        text, cls = _field_text(slot_type)
        lines.append(f"{text} {field}")
        if cls is not None:
            deps.append(cls)
    return "\n".join(lines) + "\n", deps


def ros2msg_schema(msg_class):
    """Full schema text: the type's definition, then each dependency once
    (depth first, in the order fields first mention them)."""
    text, deps = definition_text(msg_class)
    parts = [text]
    seen = {_short_name(msg_class)}
    stack = list(reversed(deps))
    while stack:
        cls = stack.pop()
        short = _short_name(cls)
        if short in seen:
            continue
        seen.add(short)
        dep_text, dep_deps = definition_text(cls)
        parts.append(f"{SEPARATOR}\nMSG: {short}\n{dep_text}")
        stack.extend(reversed(dep_deps))
    return "".join(parts)
