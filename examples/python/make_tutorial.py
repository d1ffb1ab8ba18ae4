"""Writes tutorial.ipynb from the cells below (the notebook is generated so that its source
stays reviewable as plain Python; run `python3 make_tutorial.py` after editing)."""

import nbformat

md, code = nbformat.v4.new_markdown_cell, nbformat.v4.new_code_cell

cells = [
    md(
        "# thermostamp from Python: a hemisphere, its force, its shear, a study on Dask\n\n"
        "This notebook forms the bundled hemisphere (T300 5-harness satin / PPS at 300 °C), "
        "plots the punch force, shows the shear angle on the formed part with pyvista, and "
        "runs a small process study on a Dask cluster on this machine.\n\n"
        "Install: `pip install ./python` from the repository's root, then "
        "`pip install pandas matplotlib pyvista \"dask[distributed]\"` for this notebook. "
        "Run it from `examples/python/`. Units: mm, N, s, °C. To keep it quick the blank is "
        "meshed with 10 mm cells (the example's own 4 mm cells are the converged mesh, "
        "docs/guide/forming-runs.md)."
    ),
    code(
        "import pathlib\n"
        "import thermostamp as ts\n\n"
        "examples = pathlib.Path('..').resolve()\n"
        "scenario = ts.Scenario.load(examples / 'hemisphere.toml', set={'blank.element_size': 10.0})\n"
        "scenario['process.temperature'], scenario['process.blank_holder_force']"
    ),
    md(
        "`ts.run` forms the part in this process. `progress` is called about ten times a "
        "second; Ctrl-C (the Jupyter stop button) stops the run after its step and raises "
        "`KeyboardInterrupt` with the partial result as `exception.result`. Without `output=` "
        "nothing is written to disk."
    ),
    code(
        "steps = []\n"
        "result = ts.run(scenario, progress=lambda fraction, step, time: steps.append(step))\n"
        "print(result.status, '-', len(steps), 'progress calls')\n"
        "{k: result.summary[k] for k in ['peak_punch_force', 'max_shear_deg', 'draw_in', 'waviness', 'wall_seconds']}"
    ),
    md("The history is NumPy arrays by column (`result.to_pandas()` gives a DataFrame):"),
    code(
        "import matplotlib.pyplot as plt\n\n"
        "h = result.history\n"
        "fig, ax = plt.subplots(figsize=(6, 3.5))\n"
        "ax.plot(h['stroke'], h['punch_force'], label='punch')\n"
        "ax.plot(h['stroke'], h['holder_force'], label='blank holder')\n"
        "ax.set_xlabel('stroke (mm)'); ax.set_ylabel('force (N)'); ax.legend(); ax.grid(alpha=0.3)\n"
        "ax.set_title('hemisphere, 300 °C: punch and holder forces')\n"
        "plt.show()\n"
        "result.to_pandas().tail(3)"
    ),
    md(
        "The last frame is a pyvista grid with every field of the ParaView output "
        "(`shear_angle_deg`, `thickness`, `yarn_tension_warp`, `contact_pressure`, ...), "
        "on the formed part:"
    ),
    code(
        "import pyvista as pv\n\n"
        "pv.set_jupyter_backend('static')\n"
        "grid = result.to_pyvista()\n"
        "plotter = pv.Plotter(off_screen=True, window_size=(800, 600))\n"
        "plotter.add_mesh(grid, scalars='shear_angle_deg', cmap='viridis', show_edges=True,\n"
        "                 scalar_bar_args={'title': 'shear angle (deg)'})\n"
        "plotter.view_isometric()\n"
        "plotter.show()\n"
        "print(f\"largest shear {grid.cell_data['shear_angle_deg'].max():.1f} deg\")"
    ),
    md(
        "## A study on Dask\n\n"
        "`ts.Study` runs the scenario over parameter values, each case in its own folder and "
        "its own process, on any `concurrent.futures.Executor`: here Dask's on a local "
        "cluster of two worker processes (a `dask.distributed.Client` of a real cluster, "
        "submitit's SLURM executor or Ray's fit the same way). The cases and `summary.csv` are "
        "those of `thermostamp sweep` on the same study, and a study stopped part-way "
        "resumes with what is left. A third of the stroke keeps it short."
    ),
    code(
        "from dask.distributed import Client, LocalCluster\n\n"
        "study = ts.Study(\n"
        "    examples / 'hemisphere.toml',\n"
        "    parameters={\n"
        "        'process.temperature': [280.0, 320.0],\n"
        "        'process.blank_holder_force': [50.0, 200.0],\n"
        "        'blank.element_size': [10.0],\n"
        "        'process.stroke': [10.0],\n"
        "        'output.frames': [0],\n"
        "    },\n"
        "    folder='tutorial-study',\n"
        ")\n"
        "with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \\\n"
        "        Client(cluster) as client:\n"
        "    summary = study.map(client.get_executor())\n"
        "summary.to_pandas()[['case', 'process.temperature', 'process.blank_holder_force', 'status', 'peak_punch_force', 'max_shear_deg']]"
    ),
]

notebook = nbformat.v4.new_notebook(cells=cells)
notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
nbformat.write(notebook, "tutorial.ipynb")
