"""The array type the station's numerics share.

Every vector, matrix and block of samples in the station is a float64 numpy array;
one alias, defined here once, names that type in signatures.
"""

import numpy as np
from numpy.typing import NDArray

#: A float64 numpy array of any shape (vectors, matrices, sample blocks).
FloatArray = NDArray[np.float64]
