"""Importing the core loads PyBullet only where something simulates."""

import subprocess
import sys
import textwrap

import pytest

pytestmark = pytest.mark.system


def run_python(code):
    """Run code in a fresh interpreter; return what it printed (it fails the test on error)."""
    result = subprocess.run([sys.executable, '-c', textwrap.dedent(code)], capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()


@pytest.mark.parametrize('module', ['task', 'task.genome', 'search.search', 'search.optimizers',
                                    'search.factory', 'search.hierarchy', 'run.dispatch',
                                    'run.runs', 'run.summary', 'sim.objectives', 'sim.worlds',
                                    'design', 'sim.policies'])
def test_modules_that_do_not_simulate_leave_pybullet_unloaded(module):
    printed = run_python(f"""
        import sys
        import hand_codesign.core.{module}
        import hand_codesign.core
        print('pybullet' in sys.modules, hand_codesign.core.load_task.__name__)
    """)
    assert printed == 'False load_task'


@pytest.mark.parametrize('module', ['hand_codesign.cli', 'hand_codesign.analysis.report',
                                    'hand_codesign.ros.optimizer_node',
                                    'hand_codesign.ros.recorder_node'])
def test_the_optimizer_recorder_and_analysis_leave_pybullet_unloaded(module):
    printed = run_python(f"""
        import sys
        import {module}
        print('pybullet' in sys.modules)
    """)
    assert printed == 'False'


def test_evaluate_is_reachable_from_the_package_and_loads_the_simulator():
    printed = run_python("""
        import sys
        import hand_codesign.core
        before = 'pybullet' in sys.modules
        evaluate = hand_codesign.core.evaluate
        print(before, 'pybullet' in sys.modules, callable(evaluate), evaluate.__name__)
    """)
    assert printed == 'False True True evaluate'


def test_evaluate_stays_the_function_after_its_module_was_imported_first():
    printed = run_python("""
        import hand_codesign.core.experiments.robustness  # imports the submodule core.evaluate
        from hand_codesign.core import evaluate, Simulator
        from hand_codesign.core.search import optimizers
        print(type(evaluate).__name__, Simulator.__name__, optimizers.__name__)
    """)
    assert printed == 'function Simulator hand_codesign.core.search.optimizers'


def test_unknown_name_is_an_attribute_error():
    printed = run_python("""
        import hand_codesign.core
        try:
            hand_codesign.core.no_such_name
        except AttributeError as error:
            print(error)
    """)
    assert printed == "module 'hand_codesign.core' has no attribute 'no_such_name'"


def test_the_bag_room_reads_writes_and_mends_bags_without_rclpy_or_pybullet():
    printed = run_python("""
        import sys
        import hand_codesign.bag.reader
        import hand_codesign.bag.recovery
        import hand_codesign.bag.writer
        print('rclpy' in sys.modules, 'pybullet' in sys.modules)
    """)
    assert printed == 'False False'
