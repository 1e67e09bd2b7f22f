"""
Fast decoders of CDR messages, compiled from the ``ros2msg`` schema text stored in a bag.

A bag is self-describing: each schema holds the type's .msg text and those of its
dependencies. From that text this module generates one small Python function per type that
reads the fields straight out of the serialized bytes (``struct`` for scalars, strings sliced
and decoded, primitive sequences as numpy arrays, repeated name lists shared), about three times
faster than a generic interpreter of the definition. Messages are returned as tuples in field
order (string lists as tuples); ``builtin_interfaces/Time`` and ``Duration`` become integer
nanoseconds.

Only little-endian plain CDR (XCDR1, what Fast DDS and Cyclone DDS send for ROS 2) is
compiled; ``compile_schema`` raises ``UnsupportedSchema`` for anything else (wstring, a
missing dependency), and callers fall back to a generic decoder such as mcap-ros2-support.
"""

import re
import struct

import numpy as np

DELIMITER = '=' * 80
TIME_TYPES = ('builtin_interfaces/Time', 'builtin_interfaces/Duration')
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
_ARRAY = re.compile(r'^(.*?)\[(<=)?(\d*)\]$')
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


def _normalize(type_name, package):
    """Return 'pkg/Type' for 'pkg/msg/Type', 'pkg/Type' or a bare 'Type' of package."""
    parts = type_name.split('/')
    if len(parts) == 1:
        return f'{package}/{parts[0]}'
    return f'{parts[0]}/{parts[-1]}'


def parse_msg(text, package):
    """Return the fields of one .msg text (constants and comments left out)."""
    fields = []
    for raw_line in text.splitlines():
        line = raw_line.split('#', 1)[0].strip()
        if not line:
            continue
        parts = line.split(None, 2)
        if len(parts) < 2:
            raise UnsupportedSchema(f'cannot parse the line {raw_line!r}')
        field_type, name = parts[0], parts[1]
        if '=' in name or (len(parts) > 2 and parts[2].startswith('=')):
            continue  # a constant
        array = None
        length = 0
        match = _ARRAY.match(field_type)
        if match:
            field_type, bounded, digits = match.groups()
            array = 'fixed' if digits and not bounded else 'sequence'
            length = int(digits) if array == 'fixed' else 0
        field_type = field_type.split('<=', 1)[0]  # bounded string: string<=N
        if field_type == 'wstring':
            raise UnsupportedSchema('wstring fields are not supported')
        if field_type not in PRIMITIVES and field_type != 'string':
            field_type = _normalize(field_type, package)
        fields.append(Field(name, field_type, array, length))
    return fields


def split_definitions(schema_name, text):
    """Return {'pkg/Type': .msg text} of a ros2msg schema text and its dependencies."""
    sections = text.split(f'\n{DELIMITER}\n')
    definitions = {_normalize(schema_name, ''): sections[0]}
    for section in sections[1:]:
        header, _, body = section.partition('\n')
        if not header.startswith('MSG: '):
            raise UnsupportedSchema(f'dependency section starts with {header!r}, not "MSG: "')
        definitions[_normalize(header[5:].strip(), '')] = body
    return definitions


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
        package = type_name.split('/')[0]
        fields = parse_msg(self.definitions[type_name], package)
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
    definitions = split_definitions(schema_name, text)
    top = _normalize(schema_name, '')
    return [field.name for field in parse_msg(definitions[top], top.split('/')[0])]


def compile_schema(schema_name, text):
    """
    Return decode(data: bytes) -> tuple for messages of a ros2msg schema.

    ``decode.message_end(data)`` gives where the fields end: rmw_serialize reports a length up
    to 4 bytes longer than the data when a message ends with an empty float64[] sequence.
    decode raises ``ValueError`` on a malformed message and ``UnsupportedSchema`` (also a
    ValueError) on a big-endian or XCDR2 encapsulation.
    """
    definitions = split_definitions(schema_name, text)
    generator = _Generator(definitions)
    top = generator.function_for(_normalize(schema_name, ''))
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
