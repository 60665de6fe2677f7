"""Writes examples/explore.ipynb and executes it in place, so that it is committed with its
outputs (a reader on the web sees its figures): run with a Python that has chaoscope and
`pip install .[notebook]` (scripts/test's venv has both), after editing the cells here.
`--no-execute` writes the cells alone. python/tests executes it again."""
import sys
import tempfile

import nbformat as nbf
nb = nbf.v4.new_notebook()
md, code = nbf.v4.new_markdown_cell, nbf.v4.new_code_cell
nb.cells = [
    md("# Exploring the double pendulum with chaoscope\n\n"
       "Every pixel of a map is one pendulum, integrated on the GPU (or the CPU, with a notice). "
       "Maps come back as `xarray.DataArray` with named axes and units; each carries the command "
       "line that makes it again, bit for bit. Executed in CI (`python/tests`, nbclient)."),
    code("import subprocess, sys, tempfile\n"
         "from pathlib import Path\n\n"
         "import matplotlib\n"
         "import matplotlib.pyplot as plt\n"
         "import numpy as np\n\n"
         "import chaoscope\n\n"
         "\n"
         "def log_time(m):\n"
         "    \"\"\"log10 of the flip time; never (inf) left blank.\"\"\"\n"
         "    out = np.log10(m.where(np.isfinite(m)))\n"
         "    out.attrs = {'long_name': 'log10 flip time', 'units': 'log10 s'}\n"
         "    return out\n\n"
         "chaoscope.__version__"),
    md("## The flip map\n\nStarts released from rest at (theta1, theta2); the colour is the time until an arm first flips (log scale), white never within `t_max`."),
    code("flips = chaoscope.flip_map(size=256, t_max=10)\n"
         "fig, ax = plt.subplots(figsize=(5, 4.4))\n"
         "log_time(flips).plot.imshow(ax=ax, cmap='inferno_r')\n"
         "ax.set_title(flips.attrs['long_name'])\n"
         "print(flips.attrs['command'])"),
    md("## A zoom\n\nThe same map over a small square near the boundary of the no-flip region: the fractal structure goes on."),
    code("zoom = chaoscope.flip_map(size=256, t_max=10, theta1=(1.6, 2.2), theta2=(0.6, 1.2))\n"
         "fig, ax = plt.subplots(figsize=(5, 4.4))\n"
         "log_time(zoom).plot.imshow(ax=ax, cmap='inferno_r')\n"
         "ax.set_title('zoom');"),
    md("## A clicked start's trajectory\n\nOne start of the zoom, followed on the CPU in f64, and its flip time from the map."),
    code("# A pixel that flips after 2 s.\n"
         "late = zoom.where(np.isfinite(zoom) & (zoom > 2)).stack(pixel=('theta2', 'theta1')).dropna('pixel')\n"
         "start = late.isel(pixel=len(late) // 2)\n"
         "run = chaoscope.trajectory(theta1=float(start.theta1), theta2=float(start.theta2), t_max=10, every=0.02)\n"
         "fig, ax = plt.subplots(figsize=(7, 3))\n"
         "run.theta1.plot(ax=ax, label='θ1')\n"
         "run.theta2.plot(ax=ax, label='θ2')\n"
         "ax.axvline(float(start), color='k', ls=':', label='flip (map)')\n"
         "ax.axhline(np.pi, color='grey', lw=0.5); ax.axhline(-np.pi, color='grey', lw=0.5)\n"
         "ax.legend(); ax.set_ylabel('rad');"),
    md("## The divergence map beside it\n\nThe finite-time Lyapunov exponent (1/s) of the same starts: how fast neighbours part."),
    code("ftle = chaoscope.lyapunov_map(size=256, t_max=10)\n"
         "fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))\n"
         "log_time(flips).plot.imshow(ax=axes[0], cmap='inferno_r', add_colorbar=False)\n"
         "ftle.plot.imshow(ax=axes[1], cmap='magma', vmin=0)\n"
         "axes[0].set_title('flip time'); axes[1].set_title('FTLE')\n"
         "fig.tight_layout()"),
    md("## The command line's picture\n\n`picture` draws what `chaoscope flip --annotate` draws; a notebook shows it."),
    code("chaoscope.picture(flips, annotate=True)"),
    md("## A store, lazily\n\nA bigger map goes to a Zarr store band by band (`store=`, or the command line's `--data MAP.zarr`, or many tasks: `tile=`); xarray opens it lazily."),
    code("path = Path(tempfile.mkdtemp()) / 'map.zarr'\n"
         "stored = chaoscope.flip_map(size=512, t_max=5, store=str(path), resolved=True)\n"
         "print(stored['map'].chunks)\n"
         "part = stored['map'].sel(theta1=slice(0, 3), theta2=slice(3, 0))\n"
         "fig, ax = plt.subplots(figsize=(5, 4.4))\n"
         "log_time(part).plot.imshow(ax=ax, cmap='inferno_r')\n"
         "print(f\"{float(stored['resolved'].mean()):.1%} of the pixels resolved\")"),
]
nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
if "--no-execute" not in sys.argv:
    from nbclient import NotebookClient

    # Run where its files go nowhere that matters; outputs stay in the notebook.
    with tempfile.TemporaryDirectory() as where:
        NotebookClient(nb, timeout=600, kernel_name="python3",
                       resources={"metadata": {"path": where}}).execute()
nbf.write(nb, str(__import__("pathlib").Path(__file__).with_name("explore.ipynb")))
