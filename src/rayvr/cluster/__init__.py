"""rayvr.cluster: rayvr past one GPU, on Ray (the `cluster` extra: pip install 'rayvr[cluster]').

    import rayvr.cluster as rc
    with rc.Cluster(workers=4) as cluster:                    # or address="head:6379"
        ref = rc.converge_reference("scene.glb", views=2, size=(1440, 1600), frames=256, spp=16,
                                    cluster=cluster)         # the study's reference, split by samples
        out = rc.render_views(scene, graph, views, cluster=cluster)        # split by views
        seq = rc.render_sequence(scene, graph, rc.TrajectoryViews(views, "turn", frames=120),
                                 cluster=cluster)            # split by frames
        study = rc.measure(scene, configs, cluster=cluster)  # the error study by configuration
    with rc.HostFrameSplitter(scene, graph, views, workers=2) as split:   # one frame, this host's GPUs
        timing = split.render()

Ray is imported when a Cluster starts, never at import: without it these names still import
and fail when used, with ClusterError "... needs the cluster extra: pip install 'rayvr[cluster]'".
"""
from .host_split import FrameTiming, HostFrameSplitter
from .jobs import SequenceResult, ViewsResult, render_sequence, render_views
from .payload import ScenePayload
from .pool import Cluster
from .ray_support import INSTALL_HINT, have_ray, require_ray
from .sequence import TrajectoryViews
from .shares import PinnedViews, Share
from .study import SplitReference, StudyRunner, converge_reference, measure, probe_cost_model
from .worker import RenderWorker

__all__ = ["Cluster", "FrameTiming", "HostFrameSplitter", "INSTALL_HINT", "PinnedViews", "RenderWorker",
           "ScenePayload", "SequenceResult", "Share", "SplitReference", "StudyRunner", "TrajectoryViews",
           "ViewsResult", "converge_reference", "have_ray", "measure", "probe_cost_model", "render_sequence",
           "render_views", "require_ray"]
