import glob

from setuptools import find_packages, setup

package_name = 'hand_codesign'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*']),
    package_data={'hand_codesign.ros': ['fastdds_start.xml'],
                  'hand_codesign.core.sim': ['mujoco_pd.c']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/launch', glob.glob('launch/*.launch.py')),
        ('share/' + package_name + '/config',
         glob.glob('config/*.yaml') + glob.glob('config/*.json')),   # the Foxglove layout
        ('share/' + package_name + '/config/tasks', glob.glob('config/tasks/*.yaml')),
        ('share/' + package_name + '/config/reproduce', glob.glob('config/reproduce/*.yaml')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='hand_codesign developers',
    maintainer_email='hand-codesign@example.org',
    description='Evolutionary co-design of robot hands and their control, as ROS 2 nodes.',
    license='Apache-2.0',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'optimizer = hand_codesign.commands.optimizer:main',
            'evaluator = hand_codesign.ros.evaluator_node:main',
            'recorder = hand_codesign.ros.recorder_node:main',
            'live_view = hand_codesign.ros.live_node:main',
            'robot_view = hand_codesign.ros.robot_view_node:main',
            'rig_evaluator = hand_codesign.ros.rig_evaluator_node:main',
            'sim_rig = hand_codesign.ros.sim_rig_node:main',
            'codesign = hand_codesign.cli:main',
            'hand-codesign = hand_codesign.cli:main',
        ],
    },
)
