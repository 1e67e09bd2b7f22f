"""
A bag's files and one file's records: what the reader, the mender and the metadata share.

A bag is one ``.mcap`` file or a rosbag2 bag folder of files ``<name>_<k>.mcap``, written in
the order of k (a recorder restarted by the runner continues with the next k). `bag_files`
lists a folder's files in that order, for every reader of a folder: past ``_9`` an order by
name would read ``_10`` before ``_2``. `check_start` is the one test that a file is MCAP at
all; `Records` is the one front-to-back stream of a file's records, which keeps every record
before a cut or a damaged record and says how the file ended.
"""

import pathlib
import re
import struct

from mcap.exceptions import EndOfFile
from mcap.exceptions import McapError
from mcap.stream_reader import StreamReader

MCAP_MAGIC = b'\x89MCAP0\r\n'
_FILE_INDEX = re.compile(r'_(\d+)\.mcap$')
# What a record that cannot be parsed raises inside mcap's StreamReader
_RECORD_ERRORS = (McapError, struct.error, ValueError)
_EXPECTED = 'expected a bag written by the hand_codesign recorder'


class BagError(Exception):
    """A bag that cannot be read: missing, empty, not MCAP, or not a hand_codesign run."""


class BagRecoveryError(BagError, RuntimeError):
    """A bag that cannot be recovered: without a readable start or a summary after recovery."""


def bag_files(folder):
    """
    Return the .mcap files of a bag folder in the order they were written.

    Args:
        folder: a rosbag2 bag folder (str or path).

    Returns:
        list of pathlib.Path, ordered by the index k of ``<name>_<k>.mcap`` (as a number);
        files without an index first, by name.
    """
    def order(path):
        match = _FILE_INDEX.search(path.name)
        return (int(match.group(1)) if match else -1, path.name)
    return sorted(pathlib.Path(folder).glob('*.mcap'), key=order)


def check_start(path, cut_ok=False):
    """
    Raise BagError unless the file at path starts as an MCAP file does.

    Args:
        path: the file.
        cut_ok: whether a file cut off within the magic bytes (even an empty one) passes, as
            for a recorder killed before its first flush.
    """
    try:
        with open(path, 'rb') as stream:
            start = stream.read(len(MCAP_MAGIC))
    except OSError as error:
        raise BagError(f'{path}: cannot read: {error}') from None
    if cut_ok and start == MCAP_MAGIC[:len(start)]:
        return
    if not start:
        raise BagError(f'{path}: empty file; expected an MCAP bag written by the hand_codesign '
                       'recorder')
    if start != MCAP_MAGIC:
        raise BagError(f'{path}: not an MCAP file (it starts with {start!r}, an MCAP file '
                       f'with {MCAP_MAGIC!r}); {_EXPECTED}')


class Records:
    """
    The records of one MCAP file front to back, read without seeking.

    Iterating yields every record that can be parsed and stops quietly at the first that
    cannot; afterwards `cut` says whether the file ended before its end (a killed writer) and
    `damage` holds the error of a record that could not be parsed (None when there was none).
    """

    def __init__(self, path, chunks=False):
        """
        Stream the records of the file at path.

        Args:
            path: the MCAP file.
            chunks: yield each chunk as one Chunk record (its records unread) instead of the
                records inside it, so that a damaged chunk can be skipped alone.
        """
        self.path = path
        self.chunks = chunks
        self.cut = False
        self.damage = None

    def __iter__(self):
        """Yield the records; set cut or damage where reading stops early."""
        with open(self.path, 'rb') as stream:
            try:
                yield from StreamReader(stream, emit_chunks=self.chunks).records
            except EndOfFile:
                self.cut = True
            except _RECORD_ERRORS as error:
                self.damage = error
