"""EGL device selection: the EGL device of a process's CUDA device (rayvr.gpu.egl_devices)."""
from rayvr.gpu import create_context
from rayvr.gpu.egl_devices import EglDevice, list_devices, select_device, visible_cuda_devices

NV = "EGL_NV_device_cuda EGL_EXT_device_drm"
MESA = "EGL_MESA_device_software EGL_EXT_device_drm_render_node"


def test_llvmpipe_enumerates_and_selects_a_device_a_context_opens_on(gpu):
    devices = list_devices()
    assert devices and [d.index for d in devices] == list(range(len(devices)))
    index, why = select_device(0)
    # Mesa answers no CUDA device: the default display, or else a valid index.
    assert index is None or 0 <= index < len(devices), why
    other = create_context(device_index=0 if index is None else index)
    try:
        assert other.caps.gl_version >= 450
    finally:
        other.gl.release()
        gpu.gl.__enter__()      # the session's context is the current one again


def test_cuda_ordinal_numbering_skips_the_software_device():
    # NVIDIA's driver numbers the visible GPUs from 0 (CUDA_VISIBLE_DEVICES=3,5 applied); the
    # Mesa device answers nothing. EGL device 2 is CUDA ordinal 0.
    devices = [EglDevice(0, MESA), EglDevice(1, NV, 1), EglDevice(2, NV, 0)]
    assert select_device(0, visible=["3", "5"], devices=devices)[0] == 2
    assert select_device(1, visible=["3", "5"], devices=devices)[0] == 1


def test_one_gpu_shared_by_two_workers_is_the_gpu_for_both():
    # The one-GPU machine (issue 17): Ray gives each of two workers half of GPU 0, so both see
    # CUDA_VISIBLE_DEVICES=0; a worker given no GPU (share 0) sees it unset. Every case is the
    # NVIDIA device, whether or not a software device is listed before it.
    for devices, gpu in (([EglDevice(0, NV, 0)], 0), ([EglDevice(0, MESA), EglDevice(1, NV, 0)], 1)):
        for visible in (["0"], None):
            index, why = select_device(0, visible=visible, devices=devices)
            assert index == gpu and "CUDA ordinal 0" in why, (devices, visible, why)


def test_physical_numbering_matches_the_visible_id():
    # Every GPU answers, more than are visible: the values are physical, so visible "5" is 5.
    order = [3, 0, 7, 5, 1, 2, 6, 4]
    devices = [EglDevice(i, NV, c) for i, c in enumerate(order)]
    index, why = select_device(0, visible=["5"], devices=devices)
    assert index == 3 and "physical" in why
    assert select_device(0, visible=None, devices=devices)[0] == 1      # all visible: ordinal 0


def test_no_answer_or_no_match_is_the_default_display():
    index, why = select_device(0, visible=None, devices=[EglDevice(0, MESA)])
    assert index is None and "none with EGL_NV_device_cuda" in why
    index, why = select_device(2, visible=["0", "1", "2"], devices=[EglDevice(0, NV, 0), EglDevice(1, NV, 1)])
    assert index is None and "no EGL device reports" in why
    # UUIDs in CUDA_VISIBLE_DEVICES cannot be matched physically: the ordinal is kept.
    devices = [EglDevice(i, NV, i) for i in range(4)]
    assert select_device(0, visible=["GPU-1f2e"], devices=devices)[0] == 0


def test_visible_devices_parse():
    assert visible_cuda_devices({}) is None
    assert visible_cuda_devices({"CUDA_VISIBLE_DEVICES": "2, 0"}) == ["2", "0"]
    assert visible_cuda_devices({"CUDA_VISIBLE_DEVICES": ""}) == []
