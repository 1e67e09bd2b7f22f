"""
Fast decoders of CDR messages, compiled from the ``ros2msg`` schema text stored in a bag.

A bag is self-describing: each schema holds the type's .msg text and those of its
dependencies. rosbags parses that text (``get_types_from_msg``); from its parse tree this module
generates one small Python function per type that reads the fields straight out of the
serialized bytes (``struct`` for scalars, strings sliced and decoded, primitive sequences as
numpy arrays, repeated name lists shared). Messages are returned as tuples in field order
(string lists as tuples); ``builtin_interfaces/Time`` and ``Duration`` become integer
nanoseconds.

Why this is not left to a library: on a bag of 200,000 loop messages these decoders take a
fourth (loaded machine) to a tenth (quiet machine) of the time of the rosbags typestore built
from the same schemas, and a sixth to a twenty-fifth of that of mcap-ros2-support
(``bench/bench_bag.py``); reading a run is the first step of every analysis.

Only little-endian plain CDR (XCDR1, what Fast DDS and Cyclone DDS send for ROS 2) is
compiled; ``compile_schema`` raises ``UnsupportedSchema`` for anything else (wstring, a
missing dependency, a definition rosbags cannot parse), and callers fall back to the generic
decoder of the rosbags typestore.
"""

import re
import struct

import numpy as np
from rosbags.interfaces import Nodetype
from rosbags.typesys import get_types_from_msg
from rosbags.typesys import TypesysError

TIME_TYPES = ('builtin_interfaces/msg/Time', 'builtin_interfaces/msg/Duration')
# name: (struct format, size, numpy dtype)
PRIMITIVES = {
    'bool': ('?', 1, np.bool_),
    'byte': ('B', 1, np.uint8),
    'char': ('B', 1, np.uint8),
    'int8': ('b', 1, np.int8),
    'uint8': ('B', 1, np.uint8),
    'int16': ('h', 2, np.int16),
    'uint16': ('H', 2, np.uint16),
    'int32': ('i', 4, np.int32),
    'uint32': ('I', 4, np.uint32),
    'int64': ('q', 8, np.int64),
    'uint64': ('Q', 8, np.uint64),
    'float32': ('f', 4, np.float32),
    'float64': ('d', 8, np.float64),
}
_CDR_LE_HEADERS = (b'\x00\x01\x00\x00', b'\x00\x01\x00\x01', b'\x00\x01\x00\x02',
                   b'\x00\x01\x00\x03')


class UnsupportedSchema(ValueError):
    """A schema this module cannot compile; decode its messages with a generic decoder."""


class Field:
    """One field of a message: name, base type, and array kind."""

    def __init__(self, name, base_type, array=None, length=0):
        """Describe a field; array is None, 'fixed' (length elements) or 'sequence'."""
        self.name = name
        self.base_type = base_type
        self.array = array
        self.length = length


def full_type_name(type_name):
    """Return 'pkg/msg/Type' of 'pkg/msg/Type' or 'pkg/Type'."""
    parts = type_name.split('/')
    return f'{parts[0]}/msg/{parts[1]}' if len(parts) == 2 else type_name


def _field(name, node):
    """Return the Field of one entry of a rosbags parse tree."""
    kind, detail = node
    array, length = None, 0
    if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        (kind, detail), bound = detail
        array = 'fixed' if node[0] == Nodetype.ARRAY else 'sequence'
        length = bound if array == 'fixed' else 0
    base = detail[0] if kind == Nodetype.BASE else detail
    if base == 'wstring' or base.endswith('/wstring'):
        raise UnsupportedSchema(f'field {name}: wstring fields are not supported')
    return Field(name, base, array, length)


def parse_schema(schema_name, text):
    """Return {'pkg/msg/Type': [Field, ...]} of a ros2msg schema text and its dependencies."""
    try:
        types = get_types_from_msg(text, full_type_name(schema_name))
    except (TypesysError, ValueError) as error:
        raise UnsupportedSchema(f'cannot parse the schema of {schema_name}: {error}') from None
    return {name: [_field(field_name, node) for field_name, node in fields]
            for name, (_, fields) in types.items()}


class _Generator:
    """Write the Python source of the decoder functions of a type and its dependencies."""

    def __init__(self, definitions):
        self.definitions = definitions
        self.functions = {}
        self.sources = []
        self.memos = []

    def function_for(self, type_name):
        if type_name in self.functions:
            return self.functions[type_name]
        if type_name not in self.definitions:
            raise UnsupportedSchema(f'the schema has no definition of {type_name}')
        function = '_decode_' + re.sub(r'\W', '_', type_name)
        self.functions[type_name] = function
        fields = self.definitions[type_name]
        lines = [f'def {function}(data, pos):']
        names = []
        for index, field in enumerate(fields):
            variable = f'v{index}'
            names.append(variable)
            lines.extend('    ' + line for line in self._field_lines(field, variable))
        if type_name in TIME_TYPES and len(names) == 2:
            lines.append(f'    return {names[0]} * 1000000000 + {names[1]}, pos')
        else:
            lines.append(f'    return ({", ".join(names)}{"," if len(names) == 1 else ""}), pos')
        self.sources.append('\n'.join(lines))
        return function

    def _field_lines(self, field, variable):
        base = field.base_type
        if field.array is None:
            if base == 'string':
                return ['pos += -pos & 3',
                        'length, = _unpack_uint32(data, pos)',
                        f'{variable} = data[pos + 4:pos + 3 + length].decode() if length else ""',
                        'pos += 4 + length']
            if base in PRIMITIVES:
                _, size, _ = PRIMITIVES[base]
                return _align(size) + [f'{variable}, = _unpack_{base}(data, pos)',
                                       f'pos += {size}']
            return [f'{variable}, pos = {self.function_for(base)}(data, pos)']
        if base == 'string':
            return self._string_list_lines(variable, field)
        if field.array == 'sequence':
            lines = _align(4) + ['count, = _unpack_uint32(data, pos)', 'pos += 4']
            count = 'count'
        else:
            lines = []
            count = str(field.length)
        if base in PRIMITIVES:
            _, size, _ = PRIMITIVES[base]
            # An empty sequence is not padded to its element size.
            alignment = _align(size)
            if alignment and field.array == 'sequence':
                alignment = [f'if count: {alignment[0]}']
            lines += alignment + [
                f'{variable} = _np.frombuffer(data, _dtype_{base}, {count}, pos) if {count} '
                f'else _empty_{base}',
                f'pos += {count} * {size}']
        else:
            function = self.function_for(base)
            lines += [f'{variable} = []',
                      f'for _ in range({count}):',
                      f'    item, pos = {function}(data, pos)',
                      f'    {variable}.append(item)']
        return lines

    def _string_list_lines(self, variable, field):
        # Name lists repeat message after message: when the bytes of the list (its count
        # included) equal the previous message's, the previous tuple is reused. The list starts
        # 4-aligned, so the same bytes always parse to the same strings.
        memo = f'_memo{len(self.memos)}'
        self.memos.append(memo)
        if field.array == 'sequence':
            count_lines = ['    count, = _unpack_uint32(data, pos)', '    pos += 4']
            count = 'count'
        else:
            count_lines = []
            count = str(field.length)
        return [
            'pos += -pos & 3',
            'start = pos',
            f'if {memo}[0] is not None and data[start:start + len({memo}[1])] == {memo}[1]:',
            f'    {variable} = {memo}[0]',
            f'    pos = start + len({memo}[1])',
            'else:',
        ] + count_lines + [
            '    items = []',
            f'    for _ in range({count}):',
            '        pos += -pos & 3',
            '        length, = _unpack_uint32(data, pos)',
            '        items.append(data[pos + 4:pos + 3 + length].decode() if length else "")',
            '        pos += 4 + length',
            f'    {variable} = tuple(items)',
            f'    {memo}[:] = [{variable}, bytes(data[start:pos])]',
        ]


def _align(size):
    """Return the statement aligning pos to size bytes (CDR offsets start after the header)."""
    if size == 1:
        return []
    return [f'pos += (4 - pos) & {size - 1}']


def field_names(schema_name, text):
    """Return the top-level field names of a schema, in the order of the decoded tuples."""
    return [field.name for field in parse_schema(schema_name, text)[full_type_name(schema_name)]]


def compile_schema(schema_name, text):
    """
    Return decode(data: bytes) -> tuple for messages of a ros2msg schema.

    ``decode.message_end(data)`` gives where the fields end: rmw_serialize reports a length up
    to 4 bytes longer than the data when a message ends with an empty float64[] sequence.
    decode raises ``ValueError`` on a malformed message and ``UnsupportedSchema`` (also a
    ValueError) on a big-endian or XCDR2 encapsulation.
    """
    generator = _Generator(parse_schema(schema_name, text))
    top = generator.function_for(full_type_name(schema_name))
    namespace = {'_np': np}
    namespace.update({memo: [None, b''] for memo in generator.memos})
    for name, (fmt, _, dtype) in PRIMITIVES.items():
        namespace[f'_unpack_{name}'] = struct.Struct('<' + fmt).unpack_from
        namespace[f'_dtype_{name}'] = np.dtype(dtype).newbyteorder('<')
        namespace[f'_empty_{name}'] = np.zeros(0, dtype=dtype)
    exec(compile('\n\n'.join(generator.sources), f'<cdr decoder of {schema_name}>', 'exec'),
         namespace)
    decode_body = namespace[top]

    def decode(data):
        if data[:4] not in _CDR_LE_HEADERS:
            raise UnsupportedSchema(f'encapsulation {bytes(data[:4])!r} is not plain '
                                    'little-endian CDR')
        try:
            value, end = decode_body(data, 4)
        except struct.error as error:
            raise ValueError(f'message of {len(data)} bytes ends early: {error}') from None
        if end > len(data):
            raise ValueError(f'message of {len(data)} bytes ends early (needs {end})')
        return value

    def message_end(data):
        """Return the offset just after the last field of a serialized message."""
        return decode_body(data, 4)[1]

    decode.message_end = message_end
    return decode
