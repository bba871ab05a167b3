"""Write docs/ros-interface.md from the code: every node's parameters, publishers and subscriptions.

    python scripts/gen_ros_interface.py            # (re)write docs/ros-interface.md
    python scripts/gen_ros_interface.py --check    # exit 1 when the committed file differs

Nothing here is typed by hand, so the page cannot drift from the nodes:
- nodes: every class in ``ros2_ws/src/<package>/<package>/*.py`` that calls ``declare_settings(self, Cls, ...)``;
  its name from ``super().__init__('name')``, its executable from the package's ``setup.py``;
- parameters: the fields ``declare_settings`` declares (``matrix_core.settings.settings_fields``: type, default,
  ``metadata['help']``); "run time" for the names passed as ``live=``;
- topics: every ``create_publisher`` / ``create_subscription`` call of the node class and of the helper classes it
  builds with itself (``ImageOutputs(self, s)``), read from the source (``ast``) and evaluated against the
  settings defaults, ``matrix_core.topics`` and ``matrix_ros.qos``: topic name, message type, the QoS the call
  asks for and the ``if`` it sits under. Names made at run time (a bag's topics) are listed by the parameters
  they come from.
Run it in the project's environment (``source scripts/env.sh``): it imports the node modules.
"""

import argparse
import ast
import dataclasses
import importlib
import inspect
import itertools
import re
import sys
import textwrap
import typing
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / 'ros2_ws' / 'src'
DOC = ROOT / 'docs' / 'ros-interface.md'
COMMAND = 'python scripts/gen_ros_interface.py'
ENDPOINT_CALLS = {'create_publisher': 'publishes', 'create_subscription': 'subscribes'}
VIEW = '{view}'  # what a drone's name stands for in a per-drone topic


@dataclasses.dataclass(frozen=True)
class Dynamic:
    """A value known only at run time, from these settings fields."""

    params: tuple


@dataclasses.dataclass(frozen=True)
class Alt:
    """One value an expression can take, under ``conds`` (rendered conditions), reading settings ``params``."""

    value: object
    conds: tuple = ()
    params: tuple = ()


@dataclasses.dataclass
class Endpoint:
    direction: str  # 'publishes' or 'subscribes'
    topic: object  # str (a name or pattern) or Dynamic
    msg_type: str
    qos: str
    when: str
    topic_param: str  # the parameter that names the topic ('' when fixed)


@dataclasses.dataclass
class NodeDoc:
    name: str
    module: str
    executable: str
    summary: str
    settings: type
    live: tuple
    endpoints: list


# ----------------------------------------------------------------------------------------------- discovery


def _executables() -> dict:
    """module -> ``package executable`` from the console_scripts of every package's setup.py."""
    out = {}
    for setup in sorted(SRC.glob('*/setup.py')):
        for exe, module in re.findall(r"'([\w-]+)\s*=\s*([\w.]+):main'", setup.read_text()):
            out[module] = f'{setup.parent.name} {exe}'
    return out


def _declare_call(cls: ast.ClassDef):
    for node in ast.walk(cls):
        if isinstance(node, ast.Call) and getattr(node.func, 'id', None) == 'declare_settings' and len(node.args) > 1:
            return node
    return None


def _node_name(cls: ast.ClassDef) -> str:
    for node in ast.walk(cls):
        if (
            isinstance(node, ast.Call)
            and getattr(node.func, 'attr', None) == '__init__'
            and node.args
            and isinstance(node.args[0], ast.Constant)
        ):
            return node.args[0].value
    return cls.name


def find_nodes() -> list:
    """NodeDoc of every node class of the workspace, sorted by node name."""
    executables, nodes = _executables(), []
    for path in sorted(SRC.glob('*/*/*.py')):
        if path.parent.name != path.parent.parent.name:  # only <package>/<package>/*.py
            continue
        tree = ast.parse(path.read_text())
        for cls in [c for c in tree.body if isinstance(c, ast.ClassDef)]:
            call = _declare_call(cls)
            if call is None:
                continue
            name = f'{path.parent.name}.{path.stem}'
            module = importlib.import_module(name)
            settings = eval(compile(ast.Expression(call.args[1]), str(path), 'eval'), vars(module))
            live = next((k.value for k in call.keywords if k.arg == 'live'), None)
            live = tuple(eval(compile(ast.Expression(live), str(path), 'eval'), vars(module))) if live else ()
            reader = EndpointReader(module, cls, settings)
            summary = (ast.get_docstring(tree) or '').split('\n\n')[0].replace('\n', ' ')
            nodes.append(
                NodeDoc(_node_name(cls), name, executables.get(name, ''), summary, settings, live, reader.endpoints())
            )
    return sorted(nodes, key=lambda n: n.name)


# ----------------------------------------------------------------------------------------------- evaluation


def _qos_text(qos) -> str:
    """'reliable, transient local, keep last 10' of a QoSProfile (an int is a depth, as rclpy reads it)."""
    from rclpy.qos import QoSProfile

    if isinstance(qos, Dynamic):
        return _dynamic_text(qos)
    if isinstance(qos, int) and not isinstance(qos, bool):
        qos = QoSProfile(depth=qos)
    if not isinstance(qos, QoSProfile):
        return str(qos)
    words = [qos.reliability.name.lower().replace('_', ' '), qos.durability.name.lower().replace('_', ' ')]
    history = 'keep all' if qos.history.name == 'KEEP_ALL' else f'keep last {qos.depth}'
    return ', '.join(words + [history])


def _dynamic_text(value: Dynamic) -> str:
    return 'given by ' + ', '.join(f'`{p}`' for p in value.params) if value.params else 'known at run time'


def _type_text(value) -> str:
    if isinstance(value, Dynamic):
        return _dynamic_text(value)
    if isinstance(value, str):
        return value
    if inspect.isclass(value):
        package = value.__module__.split('.')[0]
        kind = 'srv' if '.srv' in value.__module__ else 'msg'
        return f'{package}/{kind}/{value.__name__}'
    return str(value)


def _negate(cond: str) -> str:
    if cond.startswith('not '):
        return cond[4:]
    for is_, is_not in ((' == ', ' != '), (' not in ', ' in '), (' in ', ' not in ')):
        if cond.count(is_) == 1 and ' and ' not in cond and ' or ' not in cond:
            return cond.replace(is_, is_not)
    return f'not {cond}' if ' ' not in cond else f'not ({cond})'


LOOP_TAG = '__item__'  # cond of the alternatives one item of a literal loop binds: LOOP_TAG<loop>:<item>


def _consistent(conds) -> bool:
    items = {}
    for c in conds:
        if c.startswith(LOOP_TAG):
            loop, item = c[len(LOOP_TAG) :].split(':')
            if items.setdefault(loop, item) != item:  # two items of one loop at once
                return False
    return not any(_negate(c) in conds for c in conds)


class _Loop(ast.expr):
    """What a loop over a computed iterable binds: known at run time, from what ``iter`` reads."""

    _fields = ('iter',)


def _merge(alts_per_arg) -> list:
    """Every consistent combination of one alternative per argument: (values, conds, params)."""
    out = []
    for combo in itertools.product(*alts_per_arg):
        conds = tuple(dict.fromkeys(c for a in combo for c in a.conds))
        if _consistent(conds):
            out.append(([a.value for a in combo], conds, tuple(dict.fromkeys(p for a in combo for p in a.params))))
    return out


class EndpointReader:
    """The publishers and subscriptions a node class creates, evaluated from its source."""

    def __init__(self, module, cls: ast.ClassDef, settings: type):
        self.module, self.cls, self.settings = module, cls, settings
        self.fields = {f.name: f for f in dataclasses.fields(settings)}
        self.defaults = {name: default for name, _, default, _ in _settings_fields(settings)}
        self.types = {name: typ for name, typ, _, _ in _settings_fields(settings)}

    def endpoints(self) -> list:
        found = self._scan(self.cls, vars(self.module))
        for helper, namespace in self._helpers():
            found += self._scan(helper, namespace)
        return found

    def _helpers(self):
        """Classes of the workspace the node builds with itself as an argument (they create endpoints for it)."""
        for call in ast.walk(self.cls):
            if not (isinstance(call, ast.Call) and isinstance(call.func, ast.Name)):
                continue
            if not any(isinstance(a, ast.Name) and a.id == 'self' for a in call.args):
                continue
            obj = vars(self.module).get(call.func.id)
            if inspect.isclass(obj) and (SRC / obj.__module__.split('.')[0]).is_dir():
                tree = ast.parse(textwrap.dedent(inspect.getsource(obj)))
                yield tree.body[0], vars(sys.modules[obj.__module__])

    def _scan(self, cls: ast.ClassDef, namespace: dict) -> list:
        found = []
        for method in [m for m in cls.body if isinstance(m, ast.FunctionDef)]:
            env = _bindings(method, cls, self._cond_text)
            parents = {child: node for node in ast.walk(method) for child in ast.iter_child_nodes(node)}
            for call in ast.walk(method):
                if isinstance(call, ast.Call) and getattr(call.func, 'attr', None) in ENDPOINT_CALLS:
                    found += self._endpoint(call, env, parents, namespace)
        return found

    def _endpoint(self, call, env, parents, namespace) -> list:
        named = {k.arg: k.value for k in call.keywords}
        qos_at = 2 if call.func.attr == 'create_publisher' else 3  # a subscription's callback comes before
        args = [
            call.args[i] if i < len(call.args) else named.get(key, ast.Constant(10))
            for i, key in ((0, 'msg_type'), (1, 'topic'), (qos_at, 'qos_profile'))
        ]
        ctx = (env, namespace)
        types, names, qos = (self.ev(a, ctx) for a in args)
        where = self._where(call, parents)
        out = []
        for (msg_type, topic, profile), conds, params in _merge([types, names, qos]):
            topic_param = next((p for p in params if p in self._topic_params()), '')
            qos_params = [p for p in params if p not in self._topic_params() and self.types.get(p) is str]
            qos_text = _qos_text(profile)
            if qos_params:
                qos_text = f'parameter `{qos_params[-1]}` (default {self.defaults[qos_params[-1]]}: {qos_text})'
            if topic_param and self.defaults[topic_param] in ('', []):
                topic = Dynamic((topic_param,))  # an empty default: off until the parameter names a topic
            when = ' and '.join(dict.fromkeys(self._substitute(c, conds, env) for c in where + list(conds)))
            when = ' and '.join(c for c in when.split(' and ') if not c.startswith(LOOP_TAG))
            out.append(
                Endpoint(ENDPOINT_CALLS[call.func.attr], topic, _type_text(msg_type), qos_text, when, topic_param)
            )
        return out

    @staticmethod
    def _substitute(cond: str, conds, env) -> str:
        """``cond`` with the names a literal loop's item binds to constants written as those constants."""
        for name, values in env.items():
            for value, tags in values:
                if isinstance(value, ast.Constant) and tags and set(tags) <= set(conds) and name.isidentifier():
                    cond = re.sub(rf'\b{name}\b', ast.unparse(value), cond)
        return cond

    def _topic_params(self) -> set:
        return {n for n in self.fields if n.endswith('_topic') or n == 'topics'}

    def _where(self, call, parents) -> list:
        """The rendered tests of the ``if`` statements and expressions the call sits in, outermost first."""
        conds, node = [], call
        while node in parents:
            parent = parents[node]
            if isinstance(parent, (ast.If, ast.IfExp)) and node is not parent.test:
                text = self._cond_text(parent.test)
                in_body = node in (parent.body if isinstance(parent, ast.If) else [parent.body])
                conds.append(text if in_body else _negate(text))
            node = parent
        return conds[::-1]

    def _cond_text(self, test) -> str:
        """A condition as the reader knows it: settings fields by their parameter names (``s.x`` -> ``x``)."""
        return re.sub(
            r'\b(?:self\.settings|settings|s)\.(\w+)',
            lambda m: m.group(1) if m.group(1) in self.fields else m.group(0),
            ast.unparse(test),
        )

    def _field(self, node) -> str:
        """The settings field ``node`` reads (``s.x``, ``settings.x``, ``self.settings.x``), else None."""
        if not (isinstance(node, ast.Attribute) and node.attr in self.fields):
            return None
        owner = node.value
        if isinstance(owner, ast.Name) and owner.id in ('s', 'settings'):
            return node.attr
        if isinstance(owner, ast.Attribute) and owner.attr == 'settings':
            return node.attr
        return None

    def ev(self, node, ctx) -> list:
        """Every value ``node`` can take (a list of Alt)."""
        env, namespace = ctx
        if isinstance(node, ast.Constant):
            return [Alt(node.value)]
        if isinstance(node, _Loop):
            return [Alt(Dynamic(self._params_in(node.iter, env)))]
        if isinstance(node, ast.IfExp):
            text = self._cond_text(node.test)
            body = [Alt(a.value, (text,) + a.conds, a.params) for a in self.ev(node.body, ctx)]
            orelse = [Alt(a.value, (_negate(text),) + a.conds, a.params) for a in self.ev(node.orelse, ctx)]
            return body + orelse
        field = self._field(node)
        if field is not None:
            if self.types[field] is bool:
                return [Alt(True, (field,), (field,)), Alt(False, (f'not {field}',), (field,))]
            return [Alt(self.defaults[field], (), (field,))]
        key = ast.unparse(node)
        if key in env:
            return [
                Alt(a.value, conds + a.conds, a.params) for bound, conds in env[key] for a in self.ev(bound, ctx)
            ] or [Alt(Dynamic(()))]
        if isinstance(node, ast.Name):
            if node.id in namespace:
                return [Alt(namespace[node.id])]
            return [Alt(Dynamic(()))]
        if isinstance(node, ast.Attribute):
            out = []
            for a in self.ev(node.value, ctx):
                try:
                    out.append(Alt(getattr(a.value, node.attr), a.conds, a.params))
                except AttributeError:
                    out.append(Alt(Dynamic(a.params), a.conds, a.params))
            return out
        if isinstance(node, ast.Call):
            return self._ev_call(node, ctx)
        return [Alt(Dynamic(self._params_in(node, env)))]

    def _ev_call(self, node, ctx) -> list:
        env, _ = ctx
        if isinstance(node.func, ast.Attribute) and self._field(node.func) is None and node.func.attr == 'topic':
            funcs = [Alt(_pattern)]  # FuseSettings.topic: the pattern itself
        else:
            funcs = self.ev(node.func, ctx)
        args = [self.ev(a, ctx) for a in node.args]
        kwargs = {k.arg: self.ev(k.value, ctx) for k in node.keywords if k.arg}
        out = []
        for func in funcs:
            per_drone = func.value is _pattern or getattr(func.value, '__module__', '') == 'matrix_core.topics'
            for values, conds, params in _merge([[func]] + args + list(kwargs.values())):
                fn, rest = values[0], values[1:]
                positional, named = rest[: len(args)], dict(zip(kwargs, rest[len(args) :]))
                if per_drone:  # a loop's drone (or prefix) stands for every drone
                    positional = [VIEW if isinstance(v, Dynamic) else v for v in positional]
                dynamic = [v for v in positional + list(named.values()) if isinstance(v, Dynamic)]
                if dynamic or not callable(fn):
                    out.append(Alt(Dynamic(params + sum((d.params for d in dynamic), ())), conds, params))
                    continue
                try:
                    out.append(Alt(fn(*positional, **named), conds, params))
                except Exception:  # not evaluable outside a running node: known at run time only
                    out.append(Alt(Dynamic(params), conds, params))
        return out

    def _params_in(self, node, env, seen=None) -> tuple:
        """The settings fields an expression reads, through the local names it uses."""
        seen = set() if seen is None else seen
        out = []
        for sub in ast.walk(node):
            if self._field(sub) is not None:
                out.append(sub.attr)
            key = ast.unparse(sub) if isinstance(sub, (ast.Name, ast.Attribute)) else None
            if key in env and key not in seen:
                seen.add(key)
                for bound, _ in env[key]:
                    out += self._params_in(bound, env, seen)
        return tuple(dict.fromkeys(out))


def _pattern(pattern: str, view: str) -> str:
    """A per-drone topic pattern ('{view}/image_raw') stands for itself."""
    return pattern


def _bindings(method: ast.FunctionDef, cls: ast.ClassDef, cond_text) -> dict:
    """name -> [(expression, conds)] of the method's assignments and loops (also ``self.x`` of the class).

    A loop over a literal tuple binds one alternative per item; a tuple assigned from ``a if c else b`` one
    per branch; a loop over anything else leaves its names unknown (a drone, a bag's topic)."""
    env, loops = {}, {}

    def bind(target, value, conds=()):
        if isinstance(target, (ast.Tuple, ast.List)):
            if isinstance(value, ast.IfExp):
                test = cond_text(value.test)
                bind(target, value.body, conds + (test,))
                bind(target, value.orelse, conds + (_negate(test),))
            elif isinstance(value, (ast.Tuple, ast.List)) and len(value.elts) == len(target.elts):
                for t, v in zip(target.elts, value.elts):
                    bind(t, v, conds)
            else:
                for t in target.elts:
                    bind(t, None, conds)
        elif isinstance(target, (ast.Name, ast.Attribute)) and value is not None:
            env.setdefault(ast.unparse(target), []).append((value, conds))

    sources = [method] + [m for m in cls.body if isinstance(m, ast.FunctionDef) and m.name == '__init__']
    for node in itertools.chain.from_iterable(ast.walk(s) for s in sources):
        if isinstance(node, ast.Assign):
            for target in node.targets:
                if isinstance(target, ast.Name) or node in ast.walk(method):
                    bind(target, node.value)
        elif isinstance(node, ast.For) and isinstance(node.iter, (ast.Tuple, ast.List)):
            for i, item in enumerate(node.iter.elts):
                bind(node.target, item, (f'{LOOP_TAG}{id(node)}:{i}',))
        elif isinstance(node, (ast.For, ast.comprehension)):
            for name in ast.walk(node.target):
                if isinstance(name, ast.Name):
                    loops.setdefault(name.id, _Loop(iter=node.iter))
    for name, loop in loops.items():  # an assignment of the same name wins
        env.setdefault(name, [(loop, ())])
    return env


def _settings_fields(cls) -> list:
    """The parameters ``declare_settings`` declares for ``cls`` (the one list both use)."""
    from matrix_core.settings import settings_fields

    return settings_fields(cls)


# ----------------------------------------------------------------------------------------------- markdown


def _type_name(typ) -> str:
    if typing.get_origin(typ) in (list, tuple):
        return f'{typing.get_args(typ)[0].__name__}[]'
    return getattr(typ, '__name__', str(typ))


def _cell(text) -> str:
    return str(text).replace('|', '\\|').replace('\n', ' ')


def _default_text(value) -> str:
    if isinstance(value, (list, tuple)):
        return '`[' + ', '.join(repr(v) for v in value) + ']`'
    if isinstance(value, str):
        return f'`{value!r}`'
    return f'`{value}`'


def _topic_text(topic) -> str:
    return _dynamic_text(topic) if isinstance(topic, Dynamic) else f'`{topic}`'


def _endpoint_rows(endpoints, direction) -> list:
    rows = []
    for e in endpoints:
        if e.direction != direction:
            continue
        topic = _topic_text(e.topic) + (f' (`{e.topic_param}`)' if e.topic_param and isinstance(e.topic, str) else '')
        when = f'`{e.when}`' if e.when else ''
        row = f'| {topic} | {_cell(e.msg_type)} | {_cell(e.qos)} | {_cell(when)} |'
        if row not in rows:
            rows.append(row)
    return rows


def _node_section(node: NodeDoc) -> list:
    lines = [f'### `{node.name}`', '']
    run = f'`ros2 run {node.executable}`, ' if node.executable else ''
    lines += [f'{run}module `{node.module}`, settings `{node.settings.__name__}`.', '']
    if node.summary:
        lines += [node.summary, '']
    for direction in ('publishes', 'subscribes'):
        rows = _endpoint_rows(node.endpoints, direction)
        if rows:
            lines += [f'{direction.capitalize()}:', '', '| topic | type | QoS | when |', '|---|---|---|---|']
            lines += rows + ['']
    lines += ['| parameter | type | default | run time | description |', '|---|---|---|---|---|']
    for name, typ, default, help_text in _settings_fields(node.settings):
        live = 'yes' if name in node.live else 'no'
        lines.append(
            f'| `{name}` | {_type_name(typ)} | {_cell(_default_text(default))} | {live} | {_cell(help_text)} |'
        )
    return lines + ['']


def _topic_table(nodes) -> list:
    """Every fixed topic name (or default of a topic parameter) with its type and the nodes on each side."""
    topics = {}
    for node in nodes:
        for e in node.endpoints:
            if isinstance(e.topic, Dynamic):
                continue
            name = e.topic if e.topic.startswith('/') else '/' + e.topic  # as a root-namespace graph names it
            entry = topics.setdefault(name, {'types': [], 'publishes': [], 'subscribes': []})
            if e.msg_type not in entry['types']:
                entry['types'].append(e.msg_type)
            who = f'`{node.name}`' + (f' (if `{e.when}`)' if e.when else '')
            if who not in entry[e.direction]:
                entry[e.direction].append(who)
    lines = ['| topic | type | published by | subscribed by |', '|---|---|---|---|']
    for topic in sorted(topics, key=lambda t: (t.startswith('/' + VIEW), t)):
        e = topics[topic]
        lines.append(
            f'| `{topic}` | {_cell(", ".join(e["types"]))} | {_cell("; ".join(e["publishes"]) or "-")} '
            f'| {_cell("; ".join(e["subscribes"]) or "-")} |'
        )
    return lines + ['']


def render() -> str:
    """The whole of docs/ros-interface.md."""
    nodes = find_nodes()
    lines = [
        '# ROS interface',
        '',
        f'<!-- Generated by `{COMMAND}` from the code; do not edit: tests/test_ros_interface_doc.py fails when '
        'this file differs from what the command writes. -->',
        '',
        'The nodes, their parameters and the topics between them, read from the settings dataclasses, '
        '`matrix_core/topics.py` and the `create_publisher` / `create_subscription` calls of each node. '
        f'Topic names are relative: `{VIEW}/image_raw` is `/D3/image_raw` for drone D3 in the root namespace and '
        '`image_raw` for a node started in the drone\'s namespace `/D3`. A parameter in brackets after a topic '
        'renames it (its default is shown). Parameters are set with `--ros-args -p name:=value` or a YAML file; '
        'those marked "run time" also with `ros2 param set` while the node runs, all others are read-only. '
        'QoS is what each side asks for; every publisher of the workspace offers reliable, transient local '
        '(`matrix_ros.qos`).',
        '',
        '## Topics',
        '',
    ]
    lines += _topic_table(nodes)
    lines += ['## Nodes', '']
    for node in nodes:
        lines += _node_section(node)
    return '\n'.join(lines).rstrip('\n') + '\n'


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--check', action='store_true', help='exit 1 when docs/ros-interface.md differs')
    args = parser.parse_args(argv)
    text = render()
    if args.check:
        if not DOC.is_file() or DOC.read_text() != text:
            print(f'{DOC.relative_to(ROOT)} is out of date: run `{COMMAND}`', file=sys.stderr)
            return 1
        return 0
    DOC.write_text(text)
    print(f'wrote {DOC.relative_to(ROOT)}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
