from glob import glob

from setuptools import find_packages, setup

package_name = 'matrix_core'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    # Scene variants of the simulator, BEV training configs, the shipped BEV checkpoint and site files.
    package_data={
        'matrix_core.sim': ['configs/*.yaml'],
        'matrix_core.bev': ['configs/*.yaml', 'checkpoints/*.pt'],
        'matrix_core.site': ['sites/*.yaml'],
    },
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/sim_configs', glob('matrix_core/sim/configs/*.yaml')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='matrix-tracker developers',
    maintainer_email='dev@matrix-tracker.invalid',
    description='Pure-Python core of matrix-tracker: data layer, geometry, CLI.',
    license='Apache-2.0',
    entry_points={'console_scripts': ['matrix-tracker = matrix_core.cli.main:main']},
)
