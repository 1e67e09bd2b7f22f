"""
What a run's bag says about trust: forged messages ignored, audits, quarantined evaluators.

The optimizer counts in each GenerationSummary the evaluations it ignored for a missing or
wrong signature, the audit evaluations (a second or third evaluator checking an answer) and
the evaluators it quarantined; each evaluator counts in its EvaluatorStatus the RunInfos and
Candidates it ignored. The bag holds no secret key, so these counts are what it can report,
beside the GenerationSummaries the reader left out because their Ed25519 signature failed
(bag.reader). Bags of runs before signing lack these fields and report nothing here.
"""

from hand_codesign.analysis import records


def evaluator_rejections(record):
    """Return {evaluator id: messages it ignored} from the last heartbeat of each evaluator."""
    statuses = record.evaluator_status
    if not len(statuses) or 'rejected_messages' not in statuses:
        return {}
    counts = {}
    for evaluator, count in zip(statuses['evaluator_id'], statuses['rejected_messages']):
        counts[evaluator] = max(int(count), counts.get(evaluator, 0))
    return counts


def trust_counts(record):
    """Return the run's trust counts (a dict), or None for a bag without them."""
    summary = records.last_summary(record)
    if summary is None or 'audit_evaluations' not in summary:
        return None
    return {
        'rejected_evaluations': int(summary['rejected_evaluations']),
        'rejected_by_evaluators': sum(evaluator_rejections(record).values()),
        'audit_evaluations': int(summary['audit_evaluations']),
        'reevaluations': int(summary['reevaluations']),
        'quarantined': list(summary['quarantined']),
        'evaluations_told': int(summary['evaluations']),
    }


def trust_facts(record):
    """Return [(label, text)] for the report's facts: signatures, audits, quarantines."""
    forged = ([('forged summaries', f'{record.rejected_summaries} GenerationSummary '
                "message(s) in the bag failed their signature check (forged on the run's "
                'domain?) and were left out')] if record.rejected_summaries else [])
    counts = trust_counts(record)
    if counts is None:
        return forged
    told = counts['evaluations_told']
    share = f' ({counts["audit_evaluations"] / told:.0%} of the {told} told)' if told else ''
    return [
        ('rejected messages', f'{counts["rejected_evaluations"]} evaluation(s) ignored by the '
                              'optimizer (signature missing or wrong), '
                              f'{counts["rejected_by_evaluators"]} RunInfo/Candidate '
                              'message(s) ignored by the evaluators'),
        ('audits', f'{counts["audit_evaluations"]} audit evaluation(s){share}: cost, not '
                   f'progress; {counts["reevaluations"]} answer(s) of quarantined evaluators '
                   'evaluated again'),
        ('quarantined', ', '.join(counts['quarantined']) or 'none'),
    ] + forged
