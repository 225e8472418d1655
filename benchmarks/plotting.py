"""Matplotlib set up for files only (Agg), with one look for every plot."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)

COLORS = {"explicit_euler": "tab:red", "semi_implicit_euler": "tab:orange",
          "velocity_verlet": "tab:green", "rk4": "tab:blue", "adaptive": "tab:purple",
          "physics_core": "tab:blue", "pybullet": "tab:orange", "mujoco": "tab:green",
          "mujoco-cg": "tab:olive"}
MARKERS = {"explicit_euler": "o", "semi_implicit_euler": "s", "velocity_verlet": "^", "rk4": "D",
           "adaptive": "*"}


def figure(ncols=1, width=6.0, height=4.2):
    fig, axes = plt.subplots(1, ncols, figsize=(width * ncols, height), squeeze=False)
    for ax in axes[0]:
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
    return fig, list(axes[0])


def save(fig, path):
    fig.tight_layout()
    # a fixed dpi and no timestamp keep the committed PNGs stable between runs
    fig.savefig(path, dpi=90, metadata={"Software": None})
    plt.close(fig)
