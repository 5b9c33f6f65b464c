"""Run inside a container of a compose network: print when run RUN's clock says abort.

    python3 abort_watch.py RUN ENDPOINT CLIENT_CONFIG

Prints ``ready`` once subscribed, ``hearing`` at the first ``plant/step`` message of the run
that reaches it (the plant's one message a step since #28, its state inside; the route from
the run to this session is up: a subscription only printed as declared may not have reached
the router and the publishers yet), then ``abort <unix
time> <reason>`` for the first abort the orchestrator publishes on
``suscosim/RUN/orchestrator/clock``, and exits. A tap: it needs
no run key (signed messages decode without it) and only a certificate that may subscribe.

The process ends with ``os._exit`` once the abort's line is printed, never before: it used to
set the exit event first and print after, and under load the main thread woke and ended the
process in between, so the abort was heard but its line lost (the kill test's "tap heard no
abort", #30 item 17: the container had exited 0, 1.2 s after the kill, as it does when it
prints the abort; only an abort ends it before 600 s).
"""

import os
import sys
import threading
import time

import zenoh

from cosim import keys
from cosim.wire import decode

run, endpoint, config = sys.argv[1:4]
conf = zenoh.Config.from_file(config)
conf.insert_json5("connect/endpoints", f'["{endpoint}"]')
said = threading.Event()  # an abort was heard (set before its line is printed)
done = threading.Event()  # its line is printed: the main thread may end the process


def on_sample(sample) -> None:
    try:
        msg = decode(sample.payload.to_bytes())
    except Exception as exc:  # said, so that a missed abort can be told from a bad one
        print(f"undecodable {type(exc).__name__}: {exc}", flush=True)
        return
    if msg.kind != "abort":
        print(f"clock {msg.kind}", flush=True)
    if msg.kind == "abort" and not said.is_set():
        said.set()  # the first abort only (the orchestrator says it several times)
        print(f"abort {time.time():.6f} {msg.d.get('reason', '')}", flush=True)
        done.set()  # only once the line is out: the main thread exits without flushing


heard = threading.Event()
states = [0]


def on_state(_sample) -> None:
    states[0] += 1
    if not heard.is_set():
        heard.set()
        print("hearing", flush=True)


def count() -> None:  # how many plant/step it has heard, each second (for a missed abort)
    while not done.wait(1.0):
        print(f"states {states[0]} {time.time():.3f}", flush=True)


threading.Thread(target=count, daemon=True).start()


session = zenoh.open(conf)
session.declare_subscriber(keys.key(run, keys.ORCHESTRATOR, keys.CLOCK), on_sample)
session.declare_subscriber(keys.key(run, "plant", keys.STEP), on_state)
print("ready", flush=True)
done.wait(600)
sys.stdout.flush()
os._exit(0)  # a Zenoh session open at exit can hang interpreter shutdown
