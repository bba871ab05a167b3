#!/usr/bin/env python3
"""CPU inference routes for the shipped detector on one thread: the encoder (8 views at the input size) and the
BEV part (aggregation, both temporal passes, heads on the grid), each as eager torch, channels_last,
TorchScript (trace + freeze + optimize_for_inference), ONNX Runtime and OpenVINO (fp32), CPU time per call
(time.process_time, median) and the largest difference to eager torch:

    taskset -c 0 python scripts/bench_routes.py [--calls 6]

ONNX Runtime and OpenVINO are not project dependencies (measured no faster, docs/fusion.md); routes whose
package is missing are skipped. To measure them without touching the venv:
``pip install --target /tmp/routes onnxruntime openvino onnx flatbuffers protobuf openvino-telemetry`` and run
with ``PYTHONPATH=$PYTHONPATH:/tmp/routes``.
"""

import argparse
import copy
import importlib.util
import tempfile
import time
from pathlib import Path

import numpy as np
import torch
from torch import nn

from matrix_core.bev.checkpoint import load_model
from matrix_core.fusion.settings import shipped_checkpoint


class BevPart(nn.Module):
    """BevFusionNet.forward after the pooling: (pooled, previous, previous_valid) -> heads and carried features."""

    def __init__(self, model):
        super().__init__()
        self.model = model

    def forward(self, pooled, previous, valid):
        aggregated = self.model.aggregate.convs(pooled)
        out = self.model.heads(self.model.temporal(aggregated, previous, valid))
        return out['heatmap'], out['offset'], out['tracking'], self.model.temporal(aggregated, None)


def cpu_ms(fn, args, calls):
    fn(*args)
    times = []
    for _ in range(calls):
        t = time.process_time()
        fn(*args)
        times.append(time.process_time() - t)
    return 1000 * np.median(times)


def routes(module, args, tmp: Path, name: str) -> dict:
    """route name -> a callable on numpy or torch inputs returning a list of arrays."""
    out = {'eager': lambda *a: module(*a)}
    cl = copy.deepcopy(module).to(memory_format=torch.channels_last)
    out['channels_last'] = lambda *a: cl(
        *(x.contiguous(memory_format=torch.channels_last) if x.dim() == 4 else x for x in a)
    )
    out['torchscript'] = torch.jit.optimize_for_inference(torch.jit.freeze(torch.jit.trace(module, args)))
    if importlib.util.find_spec('onnxruntime') and importlib.util.find_spec('onnx'):
        import onnxruntime as ort

        path = tmp / f'{name}.onnx'
        torch.onnx.export(module, args, str(path), dynamo=False, opset_version=17)
        so = ort.SessionOptions()
        so.intra_op_num_threads = so.inter_op_num_threads = 1
        session = ort.InferenceSession(str(path), so, providers=['CPUExecutionProvider'])
        names = [i.name for i in session.get_inputs()]
        out['onnxruntime'] = lambda *a: session.run(None, {n: x.numpy() for n, x in zip(names, a)})
    if importlib.util.find_spec('openvino'):
        import openvino as ov

        compiled = ov.Core().compile_model(
            ov.convert_model(module, example_input=args),
            'CPU',
            {'INFERENCE_NUM_THREADS': 1, 'PERFORMANCE_HINT': 'LATENCY', 'INFERENCE_PRECISION_HINT': 'f32'},
        )
        request = compiled.create_infer_request()
        out['openvino'] = lambda *a: list(request.infer([x.numpy() for x in a]).values())
    return out


def as_list(result):
    result = result if isinstance(result, (list, tuple)) else [result]
    return [np.asarray(r) for r in result]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument('--calls', type=int, default=6, help='timed calls per route')
    args = p.parse_args()
    torch.set_num_threads(1)
    model, settings = load_model(shipped_checkpoint())
    rows, cols = settings.grid([-15.0, -15.0, 15.0, 15.0]).shape  # the MATRIX area: 30 m square
    g = torch.Generator().manual_seed(0)
    parts = {
        'encoder': (model.encoder, (torch.randn(8, 3, settings.image_height, settings.image_width, generator=g),)),
        'bev part': (
            BevPart(model).eval(),
            (torch.rand(1, 65, rows, cols, generator=g), torch.rand(1, 64, rows, cols, generator=g), torch.ones(1)),
        ),
    }
    print(
        f'one thread, CPU time per call (median of {args.calls}); encoder: 8 views {settings.image_width}x'
        f'{settings.image_height}; bev part: grid {cols}x{rows}'
    )
    with tempfile.TemporaryDirectory() as tmp, torch.no_grad():
        for name, (module, inputs) in parts.items():
            reference = as_list(module(*inputs))
            for route, fn in routes(module, inputs, Path(tmp), name.replace(' ', '_')).items():
                diff = max(np.abs(a - b).max() for a, b in zip(as_list(fn(*inputs)), reference))
                print(f'  {name:9s} {route:14s} {cpu_ms(fn, inputs, args.calls):7.1f} ms   max |diff| {diff:.1e}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
