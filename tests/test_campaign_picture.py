"""The sweep picture's legends stand beside the panels: no point or line of the data lies under one."""
from __future__ import annotations

from genom2bip.campaign.jobs import Job
from genom2bip.campaign.params import ModelParams
from genom2bip.campaign.pictures import draw, figure

SCALES = [1, 2, 3, 4]
TASKS = {"RFLEX.servo": (8, 25), "LaserRF.acquisition": (21, 75), "POM.fusion": (10, 50)}


def _sweep():
    """A wcet-scale sweep of three period observers and a response-times job per value, with made-up records whose
    lines fill the panels (where a legend inside them would sit on the data)."""
    jobs, records = [], {}
    params = ModelParams(paths=("sensing",))
    for n, scale in enumerate(SCALES):
        for task, (response, period) in TASKS.items():
            job = Job(id=f"o{n}{task}", model="sensing", params=params, check="observer", method="explore",
                      target=f"{task}.overrun", point=(("wcet-scale", scale),), index=len(jobs))
            jobs.append(job)
            records[job.id] = {"status": "done", "verdict": "holds" if response * scale <= period else "violated",
                               "figures": {"states": 1000 * scale ** 3}}
        job = Job(id=f"r{n}", model="sensing", params=params, check="response-times", method="explore",
                  target="response times", point=(("wcet-scale", scale),), index=len(jobs))
        jobs.append(job)
        records[job.id] = {"status": "done", "verdict": "holds", "figures": {"states": 7000 * scale ** 2},
                           "values": {t: (r * scale if r * scale <= p else "unbounded") for t, (r, p) in TASKS.items()}}
    return jobs, records


def test_no_legend_overlaps_a_panel_of_data():
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    jobs, records = _sweep()
    fig = figure("wcet-scale", jobs, records)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    panels = [ax.get_window_extent(renderer) for ax in fig.axes]
    legends = [ax.get_legend().get_window_extent(renderer) for ax in fig.axes if ax.get_legend() is not None]
    assert len(panels) == 3 and len(legends) == 2  # the states' and the response times'
    for legend in legends:
        for panel in panels:
            assert not legend.overlaps(panel), (legend, panel)


def test_the_png_is_written_with_its_legends(tmp_path):
    from matplotlib.image import imread

    jobs, records = _sweep()
    (path,) = draw(jobs, records, tmp_path)
    assert path.name == "wcet-scale.png"
    height, width = imread(path).shape[:2]
    assert width > height / 2 and height > 400  # three panels, their legends kept in (bbox_inches="tight")
