"""Launch arguments from a settings dataclass: every launch file's arguments, defaults and descriptions come
from the settings (``matrix_core.settings``), never retyped.

One argument per field (same name, default and help as the ROS parameter and the CLI flag). At launch time
the strings are parsed and validated by the dataclass itself (:func:`settings_from_launch`), so a bad value
fails before any process starts, and the node gets typed parameters.

The ``launch`` packages are imported inside the functions: this module is imported only by launch files
(``launch`` comes with a ROS install, or scripts/build_cli.sh builds it here), and the rest of
``matrix_ros`` stays importable without it.
"""

from matrix_core.settings import setting_to_string, settings_fields, settings_from_strings
from matrix_core.site.parameter import follow_site


def declare_arguments(cls, defaults: dict = None, required=()) -> list:
    """``DeclareLaunchArgument`` per field of ``cls``; ``defaults`` replaces a field's default for this launch
    file (e.g. all eight drones), ``required`` names arguments without a default (launch refuses to start
    without them)."""
    from launch.actions import DeclareLaunchArgument

    defaults = defaults or {}
    args = []
    for name, _, default, help_text in settings_fields(cls):
        if name in required:
            args.append(DeclareLaunchArgument(name, description=help_text))
        else:
            text = setting_to_string(defaults.get(name, default))
            args.append(DeclareLaunchArgument(name, default_value=text, description=help_text))
    return args


def settings_from_launch(cls, context, other_arguments=(), defaults: dict = None):
    """``cls`` filled from the launch arguments of the same names (resolved in ``context``); validated. An
    argument given on the command line that is neither a field nor in ``other_arguments`` (the launch file's
    own) is a ValueError naming it, the closest and all of them: launch would ignore it silently. With a
    ``site`` field, the arguments left at their MATRIX defaults (``defaults``: the launch file's own, see
    :func:`declare_arguments`) take the site's values (``matrix_core.site.parameter.follow_site``)."""
    from launch.substitutions import LaunchConfiguration

    names = [name for name, *_ in settings_fields(cls)]
    check_arguments(context.argv or (), [*names, *other_arguments])
    settings = settings_from_strings(cls, {name: LaunchConfiguration(name).perform(context) for name in names})
    return follow_site(settings, defaults)


def check_arguments(argv, known) -> None:
    """ValueError for each ``name:=value`` of ``argv`` whose name is not in ``known``."""
    import difflib

    unknown = [a.split(':=', 1)[0] for a in argv if ':=' in a and a.split(':=', 1)[0] not in known]
    if unknown:
        hints = [
            f'{n!r} (did you mean {m[0]!r}?)' if (m := difflib.get_close_matches(n, known, 1)) else repr(n)
            for n in unknown
        ]
        raise ValueError(
            f'unknown launch argument(s) {", ".join(hints)}; the arguments are: {", ".join(sorted(known))}'
        )


def node_parameters(settings) -> dict:
    """The settings as ``launch_ros`` parameters: tuples as lists; empty lists left out (launch_ros cannot
    type them, and an unset array parameter is the empty default of ``matrix_ros.params.declare_settings``)."""
    params = {}
    for name, *_ in settings_fields(type(settings)):
        value = getattr(settings, name)
        if isinstance(value, (list, tuple)):
            if not value:
                continue
            value = list(value)
        params[name] = value
    return params


def settings_launch_description(package: str, executable: str, cls, defaults: dict = None, required=()):
    """A launch description of one node whose parameters are the fields of ``cls``: its launch arguments
    (:func:`declare_arguments`) and the node with every resolved value as a parameter."""
    from launch import LaunchDescription
    from launch.actions import OpaqueFunction
    from launch_ros.actions import Node

    def node(context):
        settings = settings_from_launch(cls, context, defaults=defaults)
        return [
            Node(
                package=package,
                executable=executable,
                name=executable,
                output='screen',
                parameters=[node_parameters(settings)],
            )
        ]

    return LaunchDescription(declare_arguments(cls, defaults, required) + [OpaqueFunction(function=node)])
