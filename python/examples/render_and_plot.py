"""Renders the Cornell box with glint's path tracer and plots the image next to its noise.

    PYTHONPATH=build/python python3 python/examples/render_and_plot.py [out.png]
"""
import sys

import matplotlib
matplotlib.use("Agg")  # no display needed: the figure goes to a file
import matplotlib.pyplot as plt
import numpy as np

import glint

out = sys.argv[1] if len(sys.argv) > 1 else "cornell_plot.png"

# The mean radiance per pixel and the variance of that mean, float32 arrays (height, width, 3).
image, variance = glint.render("cornell", width=200, height=200, spp=32, seed=1)

# Display: clip to [0, 1] and apply a 2.2 gamma. Noise: each pixel's standard error, averaged over R, G, B.
display = np.clip(image, 0, 1) ** (1 / 2.2)
standard_error = np.sqrt(variance).mean(axis=2)

fig, (left, right) = plt.subplots(1, 2, figsize=(9, 4.2))
left.imshow(display)
left.set_title(f"Cornell box, 32 spp (glint {glint.__version__})")
noise = right.imshow(standard_error, cmap="magma", vmax=np.percentile(standard_error, 99))  # the light's edge is far above
right.set_title("standard error per pixel")
fig.colorbar(noise, ax=right, fraction=0.046)
for ax in (left, right):
    ax.axis("off")
fig.tight_layout()
fig.savefig(out, dpi=100)
print(f"mean radiance {image.mean():.4f}, wrote {out}")
