"""Noise figures of real sensors (datasheets, the EuRoC rig) as simulation presets."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

from .units import convert

__all__ = ["Preset", "PRESETS"]


@dataclass(frozen=True)
class Preset:
    """Noise figures of a sensor channel, in SI (rad/s or m/s² based units).

    Attributes
    ----------
    name : str
    sensor : str
    kind : {"gyro", "accel"}
    rate : float
        A typical sample rate (Hz) for the part.
    Q, N, B, K, R : float
        Coefficients in SI; 0 where the source gives none.
    source : str
        Where the numbers come from.
    """

    name: str
    sensor: str
    kind: str
    rate: float
    Q: float = 0.0
    N: float = 0.0
    B: float = 0.0
    K: float = 0.0
    R: float = 0.0
    source: str = ""

    @property
    def unit(self) -> str:
        return "rad/s" if self.kind == "gyro" else "m/s^2"


def _g(x: float, unit: str, to: str) -> float:
    """``x`` converted from ``unit`` to ``to`` as a float (the presets' datasheet figures to SI)."""
    return float(convert(x, unit, to))


#: Presets: datasheet noise densities (ST DT0064 lists the LSM6DSL/LSM6DSM ones,
#: high-performance mode, ±2 g for the accelerometers), the ADIS16448 datasheet and
#: the EuRoC/Kalibr values for the ADIS16448 of the EuRoC rig. Datasheets give no
#: bias instability or random walk for these parts; those terms are 0 here.
PRESETS: Mapping[str, Preset] = {
    "lsm6dsl-gyro": Preset("lsm6dsl-gyro", "ST LSM6DSL", "gyro", 416.0,
                           N=_g(4.0, "mdps/sqrt(Hz)", "rad/s/sqrt(Hz)"),
                           source="LSM6DSL datasheet: 4 mdps/√Hz (high-performance mode), as quoted in ST DT0064"),
    "lsm6dsl-accel": Preset("lsm6dsl-accel", "ST LSM6DSL", "accel", 416.0,
                            N=_g(80.0, "ug/sqrt(Hz)", "m/s^2/sqrt(Hz)"),
                            source="LSM6DSL datasheet: 80 µg/√Hz (±2 g, high-performance mode),"
                                   " as quoted in ST DT0064"),
    "lsm6dsm-gyro": Preset("lsm6dsm-gyro", "ST LSM6DSM", "gyro", 416.0,
                           N=_g(3.8, "mdps/sqrt(Hz)", "rad/s/sqrt(Hz)"),
                           source="LSM6DSM datasheet: 3.8 mdps/√Hz (high-performance mode), as quoted in ST DT0064"),
    "lsm6dsm-accel": Preset("lsm6dsm-accel", "ST LSM6DSM", "accel", 416.0,
                            N=_g(90.0, "ug/sqrt(Hz)", "m/s^2/sqrt(Hz)"),
                            source="LSM6DSM datasheet: 90 µg/√Hz (±2 g, high-performance mode),"
                                   " as quoted in ST DT0064"),
    "adis16448-gyro": Preset("adis16448-gyro", "ADI ADIS16448", "gyro", 200.0,
                             N=_g(0.0135, "deg/s/sqrt(Hz)", "rad/s/sqrt(Hz)"),
                             source="ADIS16448 datasheet: 0.0135 °/s/√Hz (ARW 0.66 °/√h)"),
    "adis16448-accel": Preset("adis16448-accel", "ADI ADIS16448", "accel", 200.0,
                              N=_g(0.23, "mg/sqrt(Hz)", "m/s^2/sqrt(Hz)"),
                              source="ADIS16448 datasheet: 0.23 mg/√Hz"),
    "euroc-gyro": Preset("euroc-gyro", "ADIS16448 (EuRoC MAV rig)", "gyro", 200.0, N=1.6968e-4, K=1.9393e-5,
                         source="EuRoC MAV dataset imu0/sensor.yaml (Kalibr): gyroscope_noise_density,"
                                " gyroscope_random_walk"),
    "euroc-accel": Preset("euroc-accel", "ADIS16448 (EuRoC MAV rig)", "accel", 200.0, N=2.0e-3, K=3.0e-3,
                          source="EuRoC MAV dataset imu0/sensor.yaml (Kalibr): accelerometer_noise_density,"
                                 " accelerometer_random_walk"),
}
