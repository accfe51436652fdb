#!/usr/bin/python3
"""An independent Modbus TCP server (pymodbus, Debian's python3-pymodbus) for the driver tests.

Prints "port N" once it listens on 127.0.0.1 (port 0 = any free one), then one JSON line per
register write: {"fc": 16, "address": 10, "values": [...]}.
Options:
  --ir A=V,A=V     preset input registers      --hr A=V,...  preset holding registers
  --echo SRC:N:DST copy the N holding registers written at SRC to input registers at DST
  --size N         registers per table (addresses >= N answer "illegal data address")
  --plant OUT:IN   a noise-free classical PI plant behind the holding registers instead of the
                   write log: the output written at HR OUT-OUT+1 (s32 mV, high word first) drives
                   --plays plays (thresholds i * 75 V / plays, relaxed at 0 V); the displacement
                   lands in HR IN-IN+1 (s32 nm, high word first), rounded to --quantum-nm counts.
                   SIGUSR1 freezes the measurement registers (a stuck converter), SIGUSR2 thaws.
                   After the port line it prints "plant {thresholds_v, weights_um_per_v, ...}".
  --delay-ms D     every request is answered D ms late (a slow device; blocks the server)
Addresses are 0-based (PDU addressing).
"""
import argparse
import asyncio
import json
import signal
import sys
import time

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.server.async_io import ModbusTcpServer


def presets(text):
    out = {}
    for item in filter(None, (text or "").split(",")):
        a, v = item.split("=")
        out[int(a, 0)] = int(v, 0)
    return out


def s32_words(value):
    v = int(value) & 0xFFFFFFFF
    return [v >> 16, v & 0xFFFF]


def s32_value(words):
    v = (words[0] << 16) | words[1]
    return v - (1 << 32) if v & 0x80000000 else v


class PiPlant:
    """y = sum_i w_i play_{r_i}(u) [um], u in V; the weights give ~45 um over 0-150 V."""

    def __init__(self, plays):
        self.r = [i * 75.0 / plays for i in range(plays)]
        self.w = [0.16 * 10.0 / plays] + [0.26 / plays * (1.0 - 0.5 * i / plays)
                                            for i in range(1, plays)]
        self.p = [0.0] * plays

    def step(self, u):
        y = 0.0
        for i, r in enumerate(self.r):
            self.p[i] = max(u - r, min(u + r, self.p[i]))
            y += self.w[i] * self.p[i]
        return y


class LoggingSlave(ModbusSlaveContext):
    def __init__(self, echo, plant=None, delay_s=0.0, **kwargs):
        super().__init__(**kwargs)
        self.echo = echo
        self.plant = plant  # (PiPlant, out address, in address, quantum nm) or None
        self.delay_s = delay_s
        self.frozen = False

    def getValues(self, fc_as_hex, address, count=1):  # noqa: N802 (pymodbus API)
        if self.delay_s > 0:
            time.sleep(self.delay_s)
        return super().getValues(fc_as_hex, address, count)

    def setValues(self, fc_as_hex, address, values):  # noqa: N802 (pymodbus API)
        super().setValues(fc_as_hex, address, values)
        if fc_as_hex in (5, 15):  # coils
            return
        if self.plant:
            plant, out, dst, quantum = self.plant
            if address <= out and address + len(values) >= out + 2 and not self.frozen:
                u = s32_value(super().getValues(3, out, 2)) * 1e-3
                y_nm = round(plant.step(u) * 1e3 / quantum) * quantum
                self.store["h"].setValues(dst, s32_words(y_nm))
            return
        print(json.dumps({"fc": fc_as_hex, "address": address, "values": list(values)}),
              flush=True)
        if self.echo:
            src, n, dst = self.echo
            words = super().getValues(3, src, n)
            self.store["i"].setValues(dst, words)


async def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--port", type=int, default=0)
    ap.add_argument("--ir", default="")
    ap.add_argument("--hr", default="")
    ap.add_argument("--echo", default="")
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--plant", default="")
    ap.add_argument("--plays", type=int, default=10)
    ap.add_argument("--quantum-nm", type=int, default=1)
    ap.add_argument("--delay-ms", type=float, default=0.0)
    args = ap.parse_args()
    ir = ModbusSequentialDataBlock(0, [0] * args.size)
    hr = ModbusSequentialDataBlock(0, [0] * args.size)
    for a, v in presets(args.ir).items():
        ir.setValues(a, [v])
    for a, v in presets(args.hr).items():
        hr.setValues(a, [v])
    echo = tuple(int(x, 0) for x in args.echo.split(":")) if args.echo else None
    plant = None
    if args.plant:
        out, dst = (int(x, 0) for x in args.plant.split(":"))
        plant = (PiPlant(args.plays), out, dst, args.quantum_nm)
    slave = LoggingSlave(echo, plant, args.delay_ms * 1e-3, ir=ir, hr=hr, zero_mode=True)
    loop = asyncio.get_running_loop()
    loop.add_signal_handler(signal.SIGUSR1, lambda: setattr(slave, "frozen", True))
    loop.add_signal_handler(signal.SIGUSR2, lambda: setattr(slave, "frozen", False))
    context = ModbusServerContext(slaves=slave, single=True)
    server = ModbusTcpServer(context, address=("127.0.0.1", args.port), allow_reuse_address=True)
    task = asyncio.create_task(server.serve_forever())
    await server.serving
    print("port", server.server.sockets[0].getsockname()[1], flush=True)
    if plant:
        print("plant", json.dumps({"thresholds_v": plant[0].r, "weights_um_per_v": plant[0].w,
                                   "quantum_nm": plant[3]}), flush=True)
    await task


if __name__ == "__main__":
    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        sys.exit(0)
