"""Layer 7, input and output: VTU/PVD files, PNG plots, atomic files, run checkpoints and the
terminal progress bar.

Example
-------
>>> from core_se3 import io
>>> sorted(io.frame_fields.__doc__.split()[:2])
['Point', 'fields']
"""
from .checkpoint import Checkpoint
from .files import (atomic_path, check_input_file, read_input_file, without_contents, write_json_atomic,
                    write_text_atomic)
from .obstacles import obstacle_surfaces, write_obstacles
from .plots import new_figure, plot_load_deflection, plot_sequence, plot_shell
from .progress import LogProgress, Progress
from .vtk import frame_fields, read_field_data, write_pvd, write_series, write_vtu

__all__ = ["write_vtu", "write_pvd", "write_series", "frame_fields", "plot_load_deflection",
           "plot_shell", "plot_sequence", "new_figure", "atomic_path", "write_text_atomic",
           "write_json_atomic", "Checkpoint", "Progress", "obstacle_surfaces", "write_obstacles",
           "read_field_data", "LogProgress", "check_input_file", "read_input_file", "without_contents"]
