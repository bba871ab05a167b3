"""The device setting (``matrix_core.device``): ``auto`` is the CPU on a machine without CUDA and says so, a GPU
the machine lacks is a clear error before any work (settings, the CLI: exit 2, one line), anything else is
rejected with the allowed values; the CPU gives the default's detections. The CPU-GPU equality tests run only
where PyTorch sees a CUDA device."""

import numpy as np
import pytest
import torch

from matrix_core.bev.checkpoint import load_model
from matrix_core.bev.data import BevFrames
from matrix_core.bev.evaluation import evaluate
from matrix_core.bev.frame_network import FrameNetwork
from matrix_core.cli.main import main as cli
from matrix_core.datasets import open_dataset
from matrix_core.device import DeviceError, DeviceSettings, check_device, model_device, resolve_device
from matrix_core.fusion.fuser import BevFuser
from matrix_core.fusion.settings import FuseSettings, shipped_checkpoint
from matrix_core.fusion.views import ViewInput

torch.set_num_threads(1)
HAS_CUDA = torch.cuda.is_available()
needs_cuda = pytest.mark.skipif(not HAS_CUDA, reason='needs a CUDA device: torch.cuda.is_available() is False')
no_cuda = pytest.mark.skipif(HAS_CUDA, reason='this machine has a CUDA device')
cpu_default = pytest.mark.skipif(HAS_CUDA, reason='the default (auto) is the GPU here: the test_gpu_* tests compare')
MISSING_GPU = f'cuda:{torch.cuda.device_count()}'  # one past the last GPU: cuda:0 on a machine without any
FRAMES = (0, 2)  # of the real sample, inclusive


def test_auto_without_cuda_is_the_cpu_and_says_so():
    said = []
    device = resolve_device('auto', said.append)
    if HAS_CUDA:
        assert device == torch.device('cuda', 0) and said == [
            f'device: auto chose cuda:0 ({torch.cuda.get_device_name(0)})'
        ]
    else:
        assert device == torch.device('cpu') and said == ['device: auto chose cpu (no CUDA device)']
    assert resolve_device('cpu', said.append) == torch.device('cpu') and len(said) == 1  # only auto reports


@no_cuda
def test_cuda_without_a_cuda_device_is_a_clear_error():
    with pytest.raises(DeviceError, match=r"device 'cuda': this machine has no CUDA device"):
        resolve_device('cuda')
    with pytest.raises(DeviceError, match='no CUDA device'):  # at construction: a node's parameter validation
        FuseSettings(device='cuda')


def test_a_gpu_past_the_last_is_an_error():
    with pytest.raises(DeviceError, match=f"device '{MISSING_GPU}': (this machine has )?no CUDA device"):
        check_device(MISSING_GPU)
    with pytest.raises(ValueError, match='no CUDA device'):
        DeviceSettings(device=MISSING_GPU)


@pytest.mark.parametrize('spec', ['gpu', 'CPU', '', ' cpu', 'cuda:', 'cuda:-1', 'cuda:0:1', 'cuda0', 'mps'])
def test_other_values_are_rejected_with_the_allowed_ones(spec):
    with pytest.raises(DeviceError, match=r"is not one of auto, cpu, cuda, cuda:N"):
        FuseSettings(device=spec)


def test_the_default_is_auto_everywhere():
    assert DeviceSettings().device == FuseSettings().device == 'auto'


def _one_line_error(capsys, argv: list, expected: str) -> None:
    assert cli(argv) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err and expected in err, err


def test_cli_refuses_a_missing_gpu_before_any_work(tmp_path, capsys):
    """evaluate, train and experiments: exit 2, one line naming the device, nothing read or written (the dataset
    and the config need not even exist)."""
    out = tmp_path / 'out'
    expected = f"device '{MISSING_GPU}'"
    _one_line_error(
        capsys,
        ['evaluate', str(tmp_path / 'none'), '--checkpoint', 'none.pt', '--out', str(out), '--device', MISSING_GPU],
        expected,
    )
    _one_line_error(capsys, ['train', '--config', 'none', '--out', str(out), '--device', MISSING_GPU], expected)
    _one_line_error(
        capsys,
        ['experiments', '--out', str(out), '--report', str(tmp_path / 'R.md'), '--device', MISSING_GPU],
        expected,
    )
    _one_line_error(capsys, ['train', '--config', 'none', '--device', 'gpu'], 'is not one of auto, cpu, cuda, cuda:N')
    assert not out.exists() and not (tmp_path / 'R.md').exists()


def test_the_network_makes_every_tensor_on_the_models_device():
    """On the meta device (shapes, no data: it stands in for a GPU here) every output of the network stays on the
    model's device: a tensor made on the CPU inside it would raise."""
    model, bev = load_model(shipped_checkpoint())
    grid = bev.grid([0.0, 0.0, 12.0, 12.0])
    net = FrameNetwork(model.to('meta'), grid.shape)
    assert net.device == model_device(model) == torch.device('meta')
    images = torch.zeros(3, 3, bev.image_height, bev.image_width)  # on the CPU: copied once
    fh = torch.eye(3).repeat(3, 1, 1)
    first = net(images, fh, torch.tensor([True, False, True]))
    second = net(images, fh, torch.ones(3, dtype=torch.bool), first)
    cells = torch.zeros(2, dtype=torch.long, device='meta')
    tracking, offset = net.heads_at(second.fused, cells, cells, offset=True)
    for t in (first.heatmap, first.carry, second.heatmap, second.fused, tracking, offset):
        assert t.device.type == 'meta'
    assert second.heatmap.shape == (1, *grid.shape) and tracking.shape == offset.shape == (2, 2)


@pytest.fixture(scope='module')
def model():
    return load_model(shipped_checkpoint())


@cpu_default
def test_fuse_on_the_cpu_gives_the_defaults_detections(matrix_sample, model):
    net, bev = model
    ds = open_dataset(matrix_sample)
    frames = [
        {v: ViewInput(ds.load_image(v, f), ds.camera(v, f).img_H_ground()) for v in ds.views}
        for f in range(FRAMES[0], FRAMES[1] + 1)
    ]
    said, runs = [], []
    for settings in (FuseSettings(area=list(ds.area)), FuseSettings(area=list(ds.area), device='cpu')):
        fuser = BevFuser(settings, net, bev, log=said.append)
        runs.append([fuser.process(0.5 * k, views) for k, views in enumerate(frames)])
    assert said == ['device: auto chose cpu (no CUDA device)']  # the default's choice, in the node's log
    for default, cpu in zip(*runs):
        assert len(default.detections) > 3  # people are found on the real frames
        np.testing.assert_array_equal(default.detections.xy, cpu.detections.xy)
        np.testing.assert_array_equal(default.heatmap, cpu.heatmap)
        assert [t.track_id for t in default.tracks] == [t.track_id for t in cpu.tracks]


@cpu_default
def test_evaluate_on_the_cpu_gives_the_defaults_detections(matrix_sample, tmp_path, capsys):
    argv = ['evaluate', str(matrix_sample), '--checkpoint', 'detector_seed1.pt', '--frames', *map(str, FRAMES)]
    assert cli([*argv, '--heatmaps', '0', '--out', str(tmp_path / 'default')]) == 0
    assert 'device: auto chose cpu (no CUDA device)' in capsys.readouterr().err  # stderr: stdout is the table
    assert cli([*argv, '--heatmaps', '0', '--out', str(tmp_path / 'cpu'), '--device', 'cpu']) == 0
    assert 'device:' not in capsys.readouterr().err
    default, cpu = ((tmp_path / name / 'detections.txt').read_text() for name in ('default', 'cpu'))
    assert len(default.splitlines()) > 10 and default == cpu


def _sorted(xy):
    return xy[np.lexsort((np.round(xy[:, 1], 2), np.round(xy[:, 0], 2)))]


@needs_cuda
def test_gpu_heatmap_logits_equal_the_cpus(matrix_sample, model):
    net, bev = model
    data = BevFrames(matrix_sample, bev, frames=range(FRAMES[0], FRAMES[1] + 1), cache_images=False)
    cpu = FrameNetwork(net.to('cpu'), data.grid.shape)
    gpu = FrameNetwork(load_model(shipped_checkpoint())[0].to(resolve_device('cuda')), data.grid.shape)
    prev_cpu = prev_gpu = None
    for frame in data.frames:
        x = data.inputs(frame)
        a = cpu(x['images'], x['feat_H_grid'], x['view_mask'], prev_cpu)
        b = gpu(x['images'], x['feat_H_grid'], x['view_mask'], prev_gpu)
        assert b.heatmap.device.type == 'cuda'
        np.testing.assert_allclose(b.heatmap.cpu().numpy(), a.heatmap.numpy(), atol=1e-3)
        prev_cpu, prev_gpu = a, b


@needs_cuda
def test_gpu_gives_the_cpus_detections(matrix_sample):
    results = []
    for device in ('cpu', 'cuda'):
        net, bev = load_model(shipped_checkpoint())
        data = BevFrames(matrix_sample, bev, frames=range(FRAMES[0], FRAMES[1] + 1), cache_images=False)
        results.append(evaluate(net.to(resolve_device(device)), data, progress=False))
    cpu, gpu = results
    assert len(cpu.detections.xy) > 10
    for frame in range(FRAMES[0], FRAMES[1] + 1):
        a, b = (r.detections.xy[r.detections.frames == frame] for r in (cpu, gpu))
        assert len(a) == len(b), frame
        np.testing.assert_allclose(_sorted(b), _sorted(a), atol=1e-3)
    assert gpu.detection.moda == pytest.approx(cpu.detection.moda)
