from glob import glob

from setuptools import find_packages, setup

package_name = 'matrix_live_view'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*.json')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='matrix-tracker developers',
    maintainer_email='dev@matrix-tracker.invalid',
    description='The live view: the graph served over the Foxglove WebSocket protocol.',
    license='Apache-2.0',
    entry_points={'console_scripts': ['live_view = matrix_live_view.live_view_node:main']},
)
