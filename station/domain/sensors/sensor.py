"""Sensor and front-end constants of the putter ([Song2006]_ Table 1).

Kionix KXM52-1050 accelerometer (±2 g, ratiometric, 3.3 V) behind a TI ADS7829
12-bit ADC: 0…4095 counts over 0…3.3 V.
"""

from typing import Final, Literal

ADC_BITS: Final = 12
ADC_MIN: Final = 0
ADC_MAX: Final = (1 << ADC_BITS) - 1  # 4095 counts
SUPPLY_V: Final = 3.3

#: 0 g offset: 1.65 V at 3.3 V supply, in counts.
NOMINAL_OFFSET_COUNTS: Final = 2048.0
#: Datasheet offset spread over −40…125 °C: ±167 mV, i.e. ±207 counts.
OFFSET_SPREAD_COUNTS: Final = 207.0
#: Sensitivity 660 mV/g at 3.3 V, in counts/g (660 mV / 3.3 V × 4096).
NOMINAL_SENSITIVITY_COUNTS_PER_G: Final = 819.2
#: Sensitivity tolerance over −40…125 °C: ±5 %.
SENSITIVITY_TOLERANCE: Final = 0.05
#: Typical cross-axis sensitivity of the KXM52.
CROSS_AXIS_TYPICAL: Final = 0.02
#: Largest temperature coefficient of the 0 g offset, counts/°C: the KXM52-1050 datasheet's
#: ±100 mV drift over −40…85 °C ([Song2006]_ Table 1) reached 65 °C from room temperature
#: (25 °C), 1.54 mV/°C, in counts (× 4096/3.3 V).
OFFSET_TEMPCO_COUNTS_PER_C: Final = 0.100 / 65.0 * 4096 / SUPPLY_V
#: Largest temperature coefficient of the sensitivity, per °C: the datasheet's ±3 % (max.)
#: over −40…85 °C reached 65 °C from room temperature.
SENSITIVITY_TEMPCO_PER_C: Final = 0.03 / 65.0
#: Gyro rate resolution of the putter's reports: one count of the int16 field is 0.02 deg/s
#: (±655 deg/s span).
GYRO_DPS_PER_LSB: Final = 0.02
#: Temperature resolution of the putter's reports: one count of the int16 field is 0.01 °C.
TEMP_C_PER_LSB: Final = 0.01
#: Samples averaged per still pose in [Song2006]_.
SAMPLES_PER_POSE: Final = 1024

#: An accelerometer or gyro axis of the unit's body frame.
Axis = Literal["x", "y", "z"]
AXES: Final[tuple[Axis, Axis, Axis]] = ("x", "y", "z")
