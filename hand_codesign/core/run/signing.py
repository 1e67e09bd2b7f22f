"""
Keys and HMAC-SHA256 signatures of a run's messages, without ROS.

Why: any process that reaches a run's ROS domain could otherwise answer candidates with made-up
objectives and take the run over, and the Fast DDS of the PyPI wheels has no DDS-Security. So
the run signs its own messages:

- `hand-codesign run` draws a random secret per run (`new_secret`, the one random draw not
  taken from the run's seed: a secret that the seed repeats would be no secret). Only the
  optimizer holds it.
- Each evaluator gets its own key, HMAC-SHA256(secret, "evaluator" 0x00 evaluator_id), so that
  one evaluator cannot sign as another, plus the run-info key HMAC-SHA256(secret, "run_info")
  to check the run's announcement. Both travel as one `Credential` (a line of JSON: the
  contents of a `key_file`, or of the HAND_CODESIGN_EVALUATOR_KEY variable of the run's own
  evaluators).
- What is signed is not the CDR of a message but a canonical byte string of its fields
  (`canonical`), so that an evaluator written in another language signs without a DDS
  library's serializer; RunInfo.msg spells the encoding.
- A Candidate's signature also covers the SHA-256 of its run's RunInfo (`run_digest`): an
  evaluator evaluates a candidate only with the task the optimizer announced, even if someone
  holding the run-info key announced another one under the same run id.
- Each evaluator signs its heartbeats (EvaluatorStatus) with its key: the optimizer takes
  them only so, and nobody can invent an evaluator or speak for one.
- What a later reader trusts, the GenerationSummaries (resume rebuilds the search from them,
  analyze draws them), needs a signature that a reader without the secret can check: the
  optimizer draws an Ed25519 key pair per run (`SummaryKey`), announces the public half in
  its RunInfo and signs every summary with the private half, which never leaves its memory.
  A reader takes the first RunInfo of the run in the bag (the run's own: a forger learns the
  run id only from it) and leaves out every summary whose signature fails (`summary_valid`).
"""

import hashlib
import hmac
import json
import secrets
import struct

from cryptography.exceptions import InvalidSignature
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey
from hand_codesign.core.contract import CANDIDATE_TYPE
from hand_codesign.core.contract import EVALUATION_TYPE
from hand_codesign.core.contract import EVALUATOR_STATUS_TYPE
from hand_codesign.core.contract import GENERATION_SUMMARY_TYPE
from hand_codesign.core.contract import RUN_INFO_TYPE
from hand_codesign.errors import UserError

SECRET_BYTES = 32
# environment variables through which a runner gives its own processes their keys
SECRET_VARIABLE = 'HAND_CODESIGN_RUN_SECRET'      # the optimizer's: the secret, hex
CREDENTIAL_VARIABLE = 'HAND_CODESIGN_EVALUATOR_KEY'  # an evaluator's: a Credential line

# The signed fields of each message, in .msg order, with their kinds: s string, u unsigned
# integer or bool, f float64; a trailing [] marks an array. Not signed: signature, stamp.
SIGNED_FIELDS = {
    RUN_INFO_TYPE: (
        ('run_id', 's'), ('task_name', 's'), ('task_yaml', 's'), ('seed', 'u'),
        ('algorithm', 's'), ('iterations', 'u'), ('population', 'u'), ('world_states', 'u'),
        ('objective_names', 's[]'), ('versions', 's[]'), ('resumed_from', 's'),
        ('engine', 's'), ('engine_version', 's'), ('summary_key', 'u[]')),
    CANDIDATE_TYPE: (
        ('run_id', 's'), ('generation', 'u'), ('candidate_id', 'u'), ('evaluator_id', 's'),
        ('attempt', 'u'), ('structure', 'u[]'), ('world_states', 'u'), ('horizon', 'f'),
        ('genome', 'f[]'), ('genome_names', 's[]'), ('design_names', 's[]'),
        ('design_values', 'f[]'), ('hand_urdf', 's'), ('controller_kind', 's'),
        ('controller_mode', 's'), ('gravity_compensation', 'u'),
        ('controller_knot_times', 'f[]'), ('controller_values', 'f[]'), ('controller_kp', 'f[]'),
        ('controller_kd', 'f[]'), ('stage', 'u'), ('held_out_worlds', 'u'),
        ('world_draw', 'u'), ('worlds_from', 'u'), ('worlds_to', 'u')),
    EVALUATION_TYPE: (
        ('run_id', 's'), ('generation', 'u'), ('candidate_id', 'u'), ('attempt', 'u'),
        ('evaluator_id', 's'), ('status', 'u'), ('reason', 's'), ('objectives', 'f[]'),
        ('objective_names', 's[]'), ('fitness', 'f'), ('collision', 'u'),
        ('unstable_worlds', 'u'), ('simulated_time', 'f'), ('wall_time', 'f'),
        ('world_objectives', 'f[]'), ('measured', 'u'), ('outcome_names', 's[]'),
        ('outcomes', 'f[]')),
    GENERATION_SUMMARY_TYPE: (
        ('run_id', 's'), ('generation', 'u'), ('structure', 'u[]'), ('check', 'u'),
        ('horizon', 'f'), ('objective_names', 's[]'), ('best', 'f[]'), ('median', 'f[]'),
        ('worst', 'f[]'), ('pareto_size', 'u'), ('pareto_front', 'f[]'),
        ('best_candidate_id', 'u'), ('best_objectives', 'f[]'), ('best_fitness', 'f'),
        ('best_genome', 'f[]'), ('told_ids', 'u[]'), ('told_objectives', 'f[]'),
        ('evaluations', 'u'), ('wall_time', 'f'), ('final', 'u'), ('stop_reason', 's'),
        ('rejected_evaluations', 'u'), ('audit_evaluations', 'u'), ('audited_ids', 'u[]'),
        ('quarantined', 's[]'), ('reevaluations', 'u'), ('told_worlds', 'u[]')),
    EVALUATOR_STATUS_TYPE: (
        ('evaluator_id', 's'), ('run_id', 's'), ('host', 's'), ('pid', 'u'), ('capacity', 'u'),
        ('load', 'u'), ('evaluations_done', 'u'), ('steps_per_second', 'f'),
        ('rejected_messages', 'u')),
}
UNSIGNED_FIELDS = ('signature', 'stamp')
# Fields added to the messages after runs were recorded (racing over the worlds): a message read
# back from an older bag lacks them and was signed without them, so they are left out of its
# canonical bytes; a message of this version always has them.
LATER_FIELDS = frozenset(('worlds_from', 'worlds_to', 'told_worlds'))


class SigningError(UserError):
    """A secret or credential that cannot be used; the message names its source."""


def _string(value):
    data = str(value).encode('utf-8')
    return struct.pack('<I', len(data)) + data


def _scalar(kind, value):
    if kind == 's':
        return _string(value)
    if kind == 'u':
        return struct.pack('<Q', int(value))
    return struct.pack('<d', float(value))


def _field(message, name):
    return message[name] if isinstance(message, dict) else getattr(message, name)


def canonical(type_name, message):
    """Return the bytes signed for a message (an object or mapping with its fields)."""
    parts = [_string(type_name)]
    for name, kind in SIGNED_FIELDS[type_name]:
        if name in LATER_FIELDS and isinstance(message, dict) and name not in message:
            continue
        value = _field(message, name)
        if kind.endswith('[]'):
            values = list(value)
            parts.append(struct.pack('<I', len(values)))
            parts.extend(_scalar(kind[0], item) for item in values)
        else:
            parts.append(_scalar(kind, value))
    return b''.join(parts)


def hmac_sha256(key, data):
    return hmac.new(key, data, hashlib.sha256).digest()


def run_digest(run_info):
    """Return the SHA-256 of a RunInfo's canonical bytes (its candidates' signatures cover it)."""
    return hashlib.sha256(canonical(RUN_INFO_TYPE, run_info)).digest()


def _valid(key, data, signature):
    return hmac.compare_digest(hmac_sha256(key, data), bytes(signature))


def new_secret():
    """Return a fresh random run secret (deliberately not from the run's seed)."""
    return secrets.token_bytes(SECRET_BYTES)


def evaluator_key(secret, evaluator_id):
    """Return the key of one evaluator: HMAC-SHA256(secret, "evaluator" 0x00 id)."""
    return hmac_sha256(secret, b'evaluator\x00' + evaluator_id.encode('utf-8'))


def run_info_key(secret):
    """Return the key that signs the run's RunInfo: HMAC-SHA256(secret, "run_info")."""
    return hmac_sha256(secret, b'run_info')


def parse_secret(text, source):
    """Return the secret of its hex text; SigningError naming source when it is not one."""
    try:
        secret = bytes.fromhex(text.strip())
    except ValueError:
        secret = b''
    if len(secret) != SECRET_BYTES:
        raise SigningError(f'{source}: expected {2 * SECRET_BYTES} hex digits (a run secret), '
                           f'got {len(text.strip())} characters')
    return secret


class RunKeys:
    """The optimizer's side: sign RunInfo and Candidates, check Evaluations."""

    def __init__(self, secret):
        self.secret = secret
        self.run_info_key = run_info_key(secret)
        self._keys = {}

    def key_of(self, evaluator_id):
        if evaluator_id not in self._keys:
            self._keys[evaluator_id] = evaluator_key(self.secret, evaluator_id)
        return self._keys[evaluator_id]

    def credential(self, evaluator_id):
        """Return the Credential an evaluator of this id needs (never the secret)."""
        return Credential(evaluator_id, self.key_of(evaluator_id), self.run_info_key)

    def sign_run_info(self, run_info):
        return hmac_sha256(self.run_info_key, canonical(RUN_INFO_TYPE, run_info))

    def sign_candidate(self, candidate, digest):
        """Return the signature of a Candidate to its addressee; digest: run_digest(RunInfo)."""
        return hmac_sha256(self.key_of(_field(candidate, 'evaluator_id')),
                           canonical(CANDIDATE_TYPE, candidate) + digest)

    def evaluation_valid(self, evaluation):
        """Return whether an Evaluation is signed with the key of its evaluator_id."""
        return _valid(self.key_of(evaluation.evaluator_id),
                      canonical(EVALUATION_TYPE, evaluation), evaluation.signature)

    def status_valid(self, status):
        """Return whether an EvaluatorStatus is signed with the key of its evaluator_id."""
        # not cached in key_of: a forger inventing ids by the thousand would fill the cache
        return _valid(evaluator_key(self.secret, status.evaluator_id),
                      canonical(EVALUATOR_STATUS_TYPE, status), status.signature)


class Credential:
    """An evaluator's side: its id, its key and the run-info key."""

    def __init__(self, evaluator_id, key, run_info_key):
        self.evaluator_id = evaluator_id
        self.key = key
        self.run_info_key = run_info_key

    def text(self):
        """Return the one line of JSON a key file holds."""
        return json.dumps({'evaluator_id': self.evaluator_id, 'key': self.key.hex(),
                           'run_info_key': self.run_info_key.hex()})

    @classmethod
    def parse(cls, text, source):
        """Return the Credential of a key file's text; SigningError naming source if malformed."""
        try:
            fields = json.loads(text)
            credential = cls(str(fields['evaluator_id']), bytes.fromhex(fields['key']),
                             bytes.fromhex(fields['run_info_key']))
        except (ValueError, KeyError, TypeError, AttributeError) as error:
            raise SigningError(f'{source}: expected a line of JSON with evaluator_id, key and '
                               f'run_info_key (as `hand-codesign run --write-key-file` writes), '
                               f'got {type(error).__name__}: {error}')
        if len(credential.key) != 32 or len(credential.run_info_key) != 32:
            raise SigningError(f'{source}: key and run_info_key must be 64 hex digits each')
        return credential

    def run_info_valid(self, run_info):
        return _valid(self.run_info_key, canonical(RUN_INFO_TYPE, run_info), run_info.signature)

    def candidate_valid(self, candidate, digest):
        """Return whether a Candidate was signed for this evaluator and this run's RunInfo."""
        return (candidate.evaluator_id == self.evaluator_id
                and _valid(self.key, canonical(CANDIDATE_TYPE, candidate) + digest,
                           candidate.signature))

    def sign_evaluation(self, evaluation):
        return hmac_sha256(self.key, canonical(EVALUATION_TYPE, evaluation))

    def sign_status(self, status):
        return hmac_sha256(self.key, canonical(EVALUATOR_STATUS_TYPE, status))


class SummaryKey:
    """The optimizer's Ed25519 key pair of one run, drawn afresh (never from the run's seed)."""

    def __init__(self):
        self._private = Ed25519PrivateKey.generate()
        self.public = self._private.public_key().public_bytes_raw()   # 32 bytes

    def sign(self, summary):
        """Return the signature (64 bytes) of a GenerationSummary (object or mapping)."""
        return self._private.sign(canonical(GENERATION_SUMMARY_TYPE, summary))


def summary_valid(public_key, summary):
    """Return whether a GenerationSummary (object or mapping) is signed under public_key."""
    try:
        Ed25519PublicKey.from_public_bytes(bytes(public_key)).verify(
            bytes(_field(summary, 'signature')), canonical(GENERATION_SUMMARY_TYPE, summary))
    except (InvalidSignature, ValueError):
        return False
    return True
