"""Keys and signatures of a run's messages: what is signed, who signs, what evaluators take."""

import hashlib
import hmac
import pathlib
import re
import struct

from hand_codesign.core import contract
from hand_codesign.core.run.evaluation_jobs import EvaluatorInbox
from hand_codesign.core.run.signing import canonical
from hand_codesign.core.run.signing import Credential
from hand_codesign.core.run.signing import GENERATION_SUMMARY_TYPE
from hand_codesign.core.run.signing import RunKeys
from hand_codesign.core.run.signing import SIGNED_FIELDS
from hand_codesign.core.run.signing import SigningError
from hand_codesign.core.run.signing import summary_valid
from hand_codesign.core.run.signing import UNSIGNED_FIELDS
from hand_codesign.ros.keys import evaluator_credential
from hand_codesign.ros.keys import OptimizerSigner
from hand_codesign.ros.keys import sign_evaluation
from hand_codesign.ros.keys import sign_status
from hand_codesign_msgs.msg import Candidate
from hand_codesign_msgs.msg import Evaluation
from hand_codesign_msgs.msg import EvaluatorStatus
from hand_codesign_msgs.msg import GenerationSummary
from hand_codesign_msgs.msg import RunInfo
import pytest

MSG_DEFS = pathlib.Path(__file__).resolve().parents[3] / 'msg_defs'
SECRET = bytes(range(32))
KINDS = {'string': 's', 'bool': 'u', 'uint8': 'u', 'uint32': 'u', 'uint64': 'u',
         'float64': 'f'}


def msg_fields(name):
    """Return [(field, type)] of a .msg file, constants and comments left out."""
    fields = []
    for line in (MSG_DEFS / f'{name}.msg').read_text().splitlines():
        line = line.split('#')[0].strip()
        if line and '=' not in line:
            field_type, field = line.split()[:2]
            fields.append((field, field_type))
    return fields


@pytest.mark.parametrize('name', ['RunInfo', 'Candidate', 'Evaluation', 'GenerationSummary',
                                  'EvaluatorStatus'])
def test_every_field_but_signature_and_stamp_is_signed_in_msg_order(name):
    # a field added to the message and forgotten here would travel unsigned
    expected = []
    for field, field_type in msg_fields(name):
        if field in UNSIGNED_FIELDS:
            continue
        base = re.sub(r'\[\]$', '', field_type)
        expected.append((field, KINDS[base] + ('[]' if base != field_type else '')))
    assert list(SIGNED_FIELDS[contract.type_name(name)]) == expected


def string(text):
    data = text.encode()
    return struct.pack('<I', len(data)) + data


def test_the_signed_bytes_are_those_the_msg_comment_spells():
    # written out from RunInfo.msg's comment, as another language would, for one Candidate
    message = Candidate(run_id='r', generation=1, candidate_id=2, evaluator_id='é', attempt=3,
                        structure=[2, 1], world_states=0, horizon=0.5, genome=[0.25],
                        genome_names=['g'])
    run = RunInfo(run_id='r', task_name='t')
    signer = OptimizerSigner(RunKeys(SECRET))
    signer.run_info(run)   # announces its summary key (drawn afresh), then signs
    summary_key = bytes(run.summary_key)
    run_bytes = (string('hand_codesign_msgs/msg/RunInfo') + string('r') + string('t')
                 + string('') + struct.pack('<Q', 0) + string('') + struct.pack('<QQQ', 0, 0, 0)
                 + struct.pack('<I', 0) * 2 + string('')
                 + string('') * 2  # engine, engine_version
                 + struct.pack('<I', 32) + b''.join(struct.pack('<Q', b) for b in summary_key))
    candidate_bytes = (
        string('hand_codesign_msgs/msg/Candidate') + string('r') + struct.pack('<QQ', 1, 2)
        + string('é') + struct.pack('<Q', 3) + struct.pack('<IQQ', 2, 2, 1)
        + struct.pack('<Q', 0) + struct.pack('<d', 0.5) + struct.pack('<Id', 1, 0.25)
        + struct.pack('<I', 1) + string('g')
        # the design in physical terms, all empty here: names, values, URDF, controller
        + struct.pack('<II', 0, 0) + string('') * 3 + struct.pack('<Q', 0)
        + struct.pack('<IIII', 0, 0, 0, 0)
        + struct.pack('<QQQ', 0, 0, 0)  # stage, held_out_worlds, world_draw
        + struct.pack('<QQ', 0, 0))  # worlds_from, worlds_to: all the worlds
    key = hmac.new(SECRET, b'evaluator\x00' + 'é'.encode(), hashlib.sha256).digest()
    expected = hmac.new(key, candidate_bytes + hashlib.sha256(run_bytes).digest(),
                        hashlib.sha256).digest()
    assert bytes(signer.candidate(message).signature) == expected
    assert bytes(run.signature) == hmac.new(
        hmac.new(SECRET, b'run_info', hashlib.sha256).digest(), run_bytes,
        hashlib.sha256).digest()


def signed_run():
    signer = OptimizerSigner(RunKeys(SECRET))
    run = signer.run_info(RunInfo(run_id='run-1', task_name='task5', task_yaml='x: 1', seed=7))
    return signer, run


def test_a_candidate_holds_only_for_its_evaluator_its_run_and_its_fields():
    signer, run = signed_run()
    keys = RunKeys(SECRET)
    mine, other = keys.credential('evaluator-0'), keys.credential('evaluator-1')
    message = signer.candidate(Candidate(run_id='run-1', candidate_id=4, genome=[0.5] * 3,
                                         evaluator_id='evaluator-0'))
    digest = signer.digest
    assert mine.candidate_valid(message, digest)
    assert not other.candidate_valid(message, digest)
    assert not mine.candidate_valid(message, hashlib.sha256(b'another RunInfo').digest())
    message.genome = [0.5, 0.5, 0.25]
    assert not mine.candidate_valid(message, digest)
    message = signer.candidate(Candidate(run_id='run-1', candidate_id=4, genome=[0.5] * 3,
                                         evaluator_id='evaluator-0', world_draw=3))
    assert mine.candidate_valid(message, digest)
    message.world_draw = 0  # other worlds than the optimizer asked for
    assert not mine.candidate_valid(message, digest)
    assert mine.run_info_valid(run)
    run.seed = 8
    assert not mine.run_info_valid(run)


def test_an_evaluation_holds_only_under_the_key_of_the_evaluator_it_names():
    keys = RunKeys(SECRET)
    answer = sign_evaluation(keys.credential('evaluator-0'), Evaluation(
        run_id='run-1', candidate_id=4, evaluator_id='evaluator-0', objectives=[0.125]))
    assert OptimizerSigner(keys).valid(answer)
    answer.evaluator_id = 'evaluator-1'        # one evaluator cannot sign as another
    assert not OptimizerSigner(keys).valid(answer)
    forged = Evaluation(run_id='run-1', candidate_id=4, evaluator_id='evaluator-0',
                        objectives=[0.0])
    assert not OptimizerSigner(keys).valid(forged)
    assert not OptimizerSigner(RunKeys(bytes(32))).valid(sign_evaluation(
        keys.credential('evaluator-0'), forged))  # a key of another run
    assert OptimizerSigner(None).valid(forged), 'an unsigned run takes every answer'


def test_a_heartbeat_holds_only_under_the_key_of_the_evaluator_it_names():
    keys = RunKeys(SECRET)
    status = sign_status(keys.credential('evaluator-0'), EvaluatorStatus(
        evaluator_id='evaluator-0', run_id='run-1', capacity=2, load=1))
    assert OptimizerSigner(keys).valid(status)
    status.capacity = 1000                      # a copy that asks for more work
    assert not OptimizerSigner(keys).valid(status)
    invented = EvaluatorStatus(evaluator_id='phantom', run_id='run-1', capacity=2)
    assert not OptimizerSigner(keys).valid(invented)
    assert OptimizerSigner(None).valid(invented), 'an unsigned run hears every evaluator'


def test_a_summary_holds_only_under_the_key_its_run_announced():
    signer, run = signed_run()
    summary = signer.summary(GenerationSummary(
        run_id='run-1', generation=2, structure=[2, 2], objective_names=['p'], best=[0.5],
        told_ids=[4, 5], told_objectives=[0.5, 0.75], best_fitness=0.5))
    assert len(summary.signature) == 64 and summary_valid(run.summary_key, summary)
    summary.told_objectives = [0.0, 0.0]
    assert not summary_valid(run.summary_key, summary)
    summary.told_objectives = [0.5, 0.75]
    other, _ = signed_run()                      # another run's key pair
    assert not summary_valid(other.summary_key.public, summary)
    assert OptimizerSigner(None).summary(summary) is summary


def test_the_inbox_of_a_keyed_evaluator_takes_only_signed_messages():
    signer, run = signed_run()
    credential = RunKeys(SECRET).credential('evaluator-0')
    inbox = EvaluatorInbox('evaluator-0', credential=credential)
    forged_run = RunInfo(run_id='run-1', task_name='task5', task_yaml='evil: 1', seed=7)
    assert inbox.run_announced(forged_run) == [] and inbox.rejected == 1
    early = signer.candidate(Candidate(run_id='run-1', candidate_id=1,
                                       evaluator_id='evaluator-0'))
    assert inbox.candidate_arrived(early) == []   # waits for its RunInfo, then is checked
    assert inbox.run_announced(run) == [early]
    assert inbox.runs['run-1'].task_yaml == 'x: 1'
    forged = Candidate(run_id='run-1', candidate_id=2, evaluator_id='evaluator-0')
    assert inbox.candidate_arrived(forged) == [] and inbox.rejected == 2
    # the forgery did not use up the (candidate, attempt) of the real one
    real = signer.candidate(Candidate(run_id='run-1', candidate_id=2,
                                      evaluator_id='evaluator-0'))
    assert inbox.candidate_arrived(real) == [real]
    assert inbox.candidate_arrived(real) == [], 'taken twice'
    assert inbox.run_announced(forged_run) == [] and inbox.rejected == 3


def test_key_files_round_trip_and_bad_ones_say_what_is_wrong(tmp_path, monkeypatch):
    credential = RunKeys(SECRET).credential('host-b')
    path = tmp_path / 'host-b.key'
    path.write_text(credential.text())
    path.chmod(0o600)
    monkeypatch.delenv('HAND_CODESIGN_EVALUATOR_KEY', raising=False)
    read, evaluator_id = evaluator_credential({'key_file': str(path), 'evaluator_id': ''})
    assert evaluator_id == 'host-b' and read.key == credential.key
    assert SECRET.hex() not in path.read_text(), 'a key file must not hold the run secret'
    with pytest.raises(SigningError, match='the key is for evaluator "host-b"'):
        evaluator_credential({'key_file': str(path), 'evaluator_id': 'host-c'})
    path.write_text('{"evaluator_id": "host-b"}')
    with pytest.raises(SigningError, match=f'key_file {path}: expected a line of JSON'):
        evaluator_credential({'key_file': str(path), 'evaluator_id': ''})
    assert evaluator_credential({'key_file': '', 'evaluator_id': 'e'}) == (None, 'e')


def test_each_evaluator_has_its_own_key():
    keys = RunKeys(SECRET)
    assert keys.key_of('evaluator-0') != keys.key_of('evaluator-1')
    assert RunKeys(bytes(32)).key_of('evaluator-0') != keys.key_of('evaluator-0')
    assert Credential.parse(keys.credential('a').text(), 'x').run_info_key == keys.run_info_key


def test_a_summary_read_back_from_a_bag_older_than_racing_still_verifies():
    # bags recorded before told_worlds existed: their summaries were signed without it, and a
    # reader decoding them with the bag's own schema gets a mapping without the field
    signer, run = signed_run()
    older = {name: kind for name, kind in SIGNED_FIELDS[GENERATION_SUMMARY_TYPE]
             if name != 'told_worlds'}
    summary = GenerationSummary(run_id='run-1', generation=2, structure=[2, 2], best=[0.5],
                                objective_names=['p'], told_ids=[4], told_objectives=[0.5])
    fields = {name: getattr(summary, name) for name in older}
    old_bytes = canonical(GENERATION_SUMMARY_TYPE, dict(fields, told_worlds=[]))
    assert canonical(GENERATION_SUMMARY_TYPE, fields) != old_bytes  # signed without the field
    signature = signer.summary_key.sign(fields)
    assert summary_valid(run.summary_key, dict(fields, signature=signature))
    # a mapping of this version's schema always has the field: dropping it is no way around it
    assert not summary_valid(run.summary_key, dict(fields, told_worlds=[3], signature=signature))
