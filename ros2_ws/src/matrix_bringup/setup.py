from glob import glob

from setuptools import find_packages, setup

package_name = 'matrix_bringup'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/launch', glob('launch/*.launch.py')),
        ('share/' + package_name + '/config', glob('config/*.yaml') + glob('config/*.xml')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='matrix-tracker developers',
    maintainer_email='dev@matrix-tracker.invalid',
    description='The matrix-tracker graph (launch file and run_graph) and the graph monitor.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'discovery_server = matrix_bringup.discovery_server:main',
            'drone = matrix_bringup.drone:main',
            'graph_monitor = matrix_bringup.graph_monitor:main',
            'run_graph = matrix_bringup.run_graph:main',
        ]
    },
)
