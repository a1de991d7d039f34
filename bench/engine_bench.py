"""Engine throughput: interactions per second on dining philosophers (N=10) and a 50-receiver broadcast.

Run ``python bench/engine_bench.py [--steps N] [--seed S]``.  For each model it
prints the rate of ``Engine.run`` with the random policy (what execution
pays) and of ``enabled`` + ``fire`` alone (what the explorer pays per edge),
plus the time to flatten, generate and compile the step.
"""
from __future__ import annotations

import argparse
import random
import time

from runtime.bip2 import parse_text
from runtime.engine import Engine, RandomPolicy


def dining(n: int) -> str:
    """N philosophers, N forks; eating and putting back are 3-party rendezvous."""
    comps = "\n".join(f"    component Phil p{i}()\n    component Fork f{i}()" for i in range(n))
    conns = "\n".join(f"    connector Three eat{i}(f{i}.take, p{i}.eat, f{(i + 1) % n}.take)\n"
                      f"    connector Three done{i}(f{i}.put, p{i}.done, f{(i + 1) % n}.put)" for i in range(n))
    return f"""package Dining
  port type Port()
  atom type Fork()
    export port Port take(), put()
    place free, busy
    initial to free
    on take from free to busy
    on put from busy to free
  end
  atom type Phil()
    data int meals
    export port Port eat(), done()
    place think, eating
    initial to think do {{ meals = 0; }}
    on eat from think to eating do {{ meals = (meals + 1) % 1000; }}
    on done from eating to think
  end
  connector type Three(Port l, Port p, Port r)
    define l p r
  end
  compound type System()
{comps}
{conns}
  end
end
"""


def broadcast(n: int) -> str:
    """One sender (trigger) and n receivers (synchrons) that get the value and go back to ready on their own."""
    params = ", ".join(f"IntPort r{i}" for i in range(n))
    define = " ".join(f"r{i}" for i in range(n))
    down = " ".join(f"r{i}.v = s.v;" for i in range(n))
    args = ", ".join(f"r{i}.rcv" for i in range(n))
    recv = ", ".join(f"r{i}()" for i in range(n))
    return f"""package Bcast
  port type Port()
  port type IntPort(int v)
  atom type Sender()
    data int v
    export port IntPort snd(v)
    place s
    initial to s do {{ v = 0; }}
    on snd from s to s do {{ v = (v + 1) % 100; }}
  end
  atom type Recv()
    data int x
    export port IntPort rcv(x)
    port Port work()
    place ready, busy
    initial to ready do {{ x = 0; }}
    on rcv from ready to busy
    on work from busy to ready
  end
  connector type B(IntPort s, {params})
    define s' {define}
    on s {define} down {{ {down} }}
  end
  compound type System()
    component Sender snd()
    component Recv {recv}
    connector B bc(snd.snd, {args})
  end
end
"""


def measure(name: str, text: str, steps: int, seed: int) -> None:
    t0 = time.perf_counter()
    package = parse_text(text, f"{name}.bip")
    parse = time.perf_counter() - t0
    t0 = time.perf_counter()
    engine = Engine(package)
    build = time.perf_counter() - t0
    # enabled + fire alone, on a fresh engine (interactions are created as they are first met)
    rng = random.Random(seed)
    s = engine.initial_state()
    enabled, fire = engine.enabled, engine.fire
    t0 = time.perf_counter()
    for _ in range(steps):
        en = enabled(s)
        s = fire(s, en[rng.randrange(len(en))])
    step_rate = steps / (time.perf_counter() - t0)
    engine = Engine(package)
    t0 = time.perf_counter()
    summary = engine.run(RandomPolicy(seed), limit=steps)
    run_rate = summary.steps / (time.perf_counter() - t0)
    print(f"{name:26s} parse {parse * 1000:6.1f} ms  flatten+generate+compile {build * 1000:6.1f} ms  "
          f"run {run_rate:8.0f} interactions/s  enabled+fire {step_rate:8.0f} steps/s  ({summary.steps} steps)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    measure("dining philosophers N=10", dining(10), args.steps, args.seed)
    measure("broadcast, 50 receivers", broadcast(50), args.steps, args.seed)


if __name__ == "__main__":
    main()
