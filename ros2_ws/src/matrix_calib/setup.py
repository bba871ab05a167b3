from glob import glob

from setuptools import find_packages, setup

package_name = 'matrix_calib'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/launch', glob('launch/*.launch.py')),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='matrix-tracker developers',
    maintainer_email='dev@matrix-tracker.invalid',
    description=(
        'Per-drone camera calibration from ground checkerboards, every frame (PnP): '
        'publishes CameraInfo, pose and diagnostics.'
    ),
    license='Apache-2.0',
    # Node executables are added here by the issue that implements each node.
    entry_points={'console_scripts': ['calib = matrix_calib.calib_node:main']},
)
