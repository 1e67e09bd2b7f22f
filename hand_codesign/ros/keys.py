"""
The keys of a node and the signatures of its messages (hand_codesign.core.run.signing) over ROS.

A run's own processes get their keys from `hand-codesign run` through an environment variable
(see hand_codesign.ros.runner for why), which is removed from the node's environment once
read; an evaluator on another host reads its Credential from the file of its `key_file`
parameter. A node without any key works unsigned: an optimizer then takes every answer (and
warns), an evaluator every candidate.
"""

import array
import os
import pathlib
import socket
import stat

from hand_codesign.core.run.signing import Credential
from hand_codesign.core.run.signing import CREDENTIAL_VARIABLE
from hand_codesign.core.run.signing import parse_secret
from hand_codesign.core.run.signing import run_digest
from hand_codesign.core.run.signing import RunKeys
from hand_codesign.core.run.signing import SECRET_VARIABLE
from hand_codesign.core.run.signing import SigningError
from hand_codesign.core.run.signing import SummaryKey
from hand_codesign_msgs.msg import EvaluatorStatus


def _bytes(signature):
    return array.array('B', signature)


class OptimizerSigner:
    """
    Sign the optimizer's messages, check those of its evaluators.

    Signed: RunInfo, Candidates, GenerationSummaries; checked: Evaluations and EvaluatorStatus
    heartbeats (all pass in an unsigned run).
    """

    def __init__(self, keys):
        self.keys = keys
        self.summary_key = SummaryKey() if keys is not None else None
        self.digest = b''
        self.note = ('' if keys is not None else
                     '; UNSIGNED run (no run secret): any answer on the domain is taken')

    @classmethod
    def from_environment(cls):
        text = os.environ.pop(SECRET_VARIABLE, '')
        return cls(RunKeys(parse_secret(text, SECRET_VARIABLE)) if text else None)

    def run_info(self, message):
        """Return the RunInfo signed; its digest is what the candidates' signatures cover."""
        if self.keys is not None:
            message.summary_key = _bytes(self.summary_key.public)
            message.signature = _bytes(self.keys.sign_run_info(message))
            self.digest = run_digest(message)
        return message

    def candidate(self, message):
        if self.keys is not None:
            message.signature = _bytes(self.keys.sign_candidate(message, self.digest))
        return message

    def summary(self, message):
        if self.keys is not None:
            message.signature = _bytes(self.summary_key.sign(message))
        return message

    def valid(self, message):
        """Return whether an Evaluation or an EvaluatorStatus is signed by its evaluator."""
        if self.keys is None:
            return True
        if isinstance(message, EvaluatorStatus):
            return self.keys.status_valid(message)
        return self.keys.evaluation_valid(message)


def evaluator_credential(settings):
    """
    Return (Credential or None, evaluator id) of an evaluator node's settings.

    key_file: the parameter (a file a run wrote with --write-key-file); empty: the variable
    the runner set, or no key. The credential fixes the evaluator id; a different non-empty
    evaluator_id parameter is an error (the key would not match it). Without a key, the id is
    the parameter's or <host>-<pid>.
    """
    key_file, evaluator_id = settings['key_file'], settings['evaluator_id']
    text = os.environ.pop(CREDENTIAL_VARIABLE, '')
    source = CREDENTIAL_VARIABLE
    if key_file:
        text, source = read_key_file(pathlib.Path(key_file)), f'key_file {key_file}'
    if not text:
        return None, evaluator_id or f'{socket.gethostname()}-{os.getpid()}'
    credential = Credential.parse(text, source)
    if evaluator_id and evaluator_id != credential.evaluator_id:
        raise SigningError(f'{source}: the key is for evaluator "{credential.evaluator_id}", '
                           f'but parameter evaluator_id is "{evaluator_id}"')
    return credential, credential.evaluator_id


def read_key_file(path):
    """Return the text of a key file, which must be a file that only its owner can read."""
    if not path.is_file():
        raise SigningError(f'parameter key_file: {path} is not a file')
    try:
        mode = stat.S_IMODE(path.stat().st_mode)
        if mode & 0o077:
            raise SigningError(
                f'parameter key_file: {path} has mode {mode:04o}, so other users may read the '
                f'key; expected 0600 as `hand-codesign run --write-key-file` writes it '
                f'(chmod 600 {path})')
        return path.read_text()
    except (OSError, UnicodeDecodeError) as error:
        raise SigningError(f'parameter key_file: {path}: cannot read it: {error}') from None


def sign_evaluation(credential, message):
    """Return the Evaluation signed with the evaluator's key (unchanged when unsigned)."""
    if credential is not None:
        message.signature = _bytes(credential.sign_evaluation(message))
    return message


def sign_status(credential, message):
    """Return the EvaluatorStatus signed with the evaluator's key (unchanged when unsigned)."""
    if credential is not None:
        message.signature = _bytes(credential.sign_status(message))
    return message
