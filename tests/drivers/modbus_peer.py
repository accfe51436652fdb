#!/usr/bin/python3
"""An independent Modbus TCP server (pymodbus, Debian's python3-pymodbus) for the driver tests.

Prints "port N" once it listens on 127.0.0.1 (port 0 = any free one), then one JSON line per
register write: {"fc": 16, "address": 10, "values": [...]}.
Options:
  --ir A=V,A=V     preset input registers      --hr A=V,...  preset holding registers
  --echo SRC:N:DST copy the N holding registers written at SRC to input registers at DST
  --size N         registers per table (addresses >= N answer "illegal data address")
Addresses are 0-based (PDU addressing).
"""
import argparse
import asyncio
import json
import sys

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.server.async_io import ModbusTcpServer


def presets(text):
    out = {}
    for item in filter(None, (text or "").split(",")):
        a, v = item.split("=")
        out[int(a, 0)] = int(v, 0)
    return out


class LoggingSlave(ModbusSlaveContext):
    def __init__(self, echo, **kwargs):
        super().__init__(**kwargs)
        self.echo = echo

    def setValues(self, fc_as_hex, address, values):  # noqa: N802 (pymodbus API)
        super().setValues(fc_as_hex, address, values)
        if fc_as_hex in (5, 15):  # coils
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
    args = ap.parse_args()
    ir = ModbusSequentialDataBlock(0, [0] * args.size)
    hr = ModbusSequentialDataBlock(0, [0] * args.size)
    for a, v in presets(args.ir).items():
        ir.setValues(a, [v])
    for a, v in presets(args.hr).items():
        hr.setValues(a, [v])
    echo = tuple(int(x, 0) for x in args.echo.split(":")) if args.echo else None
    slave = LoggingSlave(echo, ir=ir, hr=hr, zero_mode=True)
    context = ModbusServerContext(slaves=slave, single=True)
    server = ModbusTcpServer(context, address=("127.0.0.1", args.port), allow_reuse_address=True)
    task = asyncio.create_task(server.serve_forever())
    await server.serving
    print("port", server.server.sockets[0].getsockname()[1], flush=True)
    await task


if __name__ == "__main__":
    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        sys.exit(0)
