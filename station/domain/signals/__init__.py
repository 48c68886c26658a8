"""The signals: what the putter's stream says, before anything is calibrated.

A block of samples and a window's summary (``samples``), whether a window is still
(``stillness``), the named poses (``poses``) and which way the putter lies
(``orientation``), and pose files (``posefile``). Imports only the sensors.
"""
