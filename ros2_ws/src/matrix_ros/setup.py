from glob import glob

from setuptools import find_packages, setup

package_name = 'matrix_ros'

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
    description='ROS 2 glue shared by the matrix-tracker nodes.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'dataset_player = matrix_ros.dataset_player:main',
            'bag_player = matrix_ros.bag_player:main',
            'recorder = matrix_ros.recorder:main',
            'link_sender = matrix_ros.link_sender:main',
        ]
    },
)
