"""somarm: self-organising-map reinforcement learning for continuous actions (Smith, 2002).

Importing the package is light: matplotlib and meshcat load only in the modules that
plot and view, and MuJoCo only in the tasks.
"""

__version__ = "0.1.0"
__all__ = ["__version__"]
