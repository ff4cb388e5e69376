"""Opening serial ports with errors that tell a person what to do, shared by the serial backends."""

from __future__ import annotations

import errno
import os

import serial

from particlebot.radio.base import PortBusyError, PortNotFoundError, PortPermissionError, RadioError

LIST_PORTS_HINT = "list ports with: python -m serial.tools.list_ports -v"


def quiet_hint(baud: int) -> str:
    """What to check when a base-station XBee at this baud hears nothing at all."""
    return (
        f"Check that the base XBee's serial rate is {baud} baud (BD=3 is 9600; otherwise add "
        "?baud=N to the URL), that it has the particles' PAN ID (ID) and channel (CH), and that "
        "the particles are switched on."
    )


def port_present(port: str) -> bool:
    """Whether the device node exists (a USB adapter that was unplugged has none)."""
    if os.name == "nt":  # COM ports have no path; try opening instead.
        return True
    return os.path.exists(port)


def translate_open_error(port: str, exc: BaseException) -> RadioError:
    code = getattr(exc, "errno", None)
    text = str(exc)
    if code == errno.ENOENT or "No such file" in text or "FileNotFoundError" in text:
        return PortNotFoundError(
            f"No serial port {port}. Plug in the XBee (in its XBee Explorer) and check the "
            f"name; {LIST_PORTS_HINT}"
        )
    if code in (errno.EACCES, errno.EPERM) or "Permission denied" in text:
        return PortPermissionError(
            f"No permission to open {port}. On Linux add yourself to the port's group "
            f"(sudo usermod -aG dialout $USER, then log in again)."
        )
    if code in (errno.EAGAIN, errno.EBUSY) or "exclusively lock" in text:
        return PortBusyError(
            f"{port} is in use by another program (XCTU, another particlebot console, a serial "
            f"monitor). Close it and try again."
        )
    return RadioError(f"Could not open {port}: {text}. {LIST_PORTS_HINT}")


def open_serial(port: str, baud: int, timeout: float) -> serial.Serial:
    """Opens port exclusively, raising a RadioError subclass with advice on failure."""
    try:
        return serial.Serial(port=port, baudrate=baud, timeout=timeout, exclusive=True)
    except (serial.SerialException, OSError, ValueError) as exc:
        raise translate_open_error(port, exc) from exc
