#!/usr/bin/env python3
"""Training speed of the learning module's networks beside the same networks
in python3-torch (Debian's, on the same libtorch 1.13 and OpenBLAS).

Runs manibench_learning_bench (C++) and this file's PyTorch twin of each
network alternately, `--pairs` times, and prints iterations per second
(BC updates: forward, MSE, backward, Adam) and the latency of one action.
The twins are the networks of learning/src/networks.cpp written the direct
way, as ManiSkill-Learn writes them (every PointNet sees every point, the
state concatenated to each point): the same parameters, the same outputs
up to rounding. `--definition` runs the C++ side that way too.

`sac:BATCH` in --nets times SAC's gradient step instead (learning/src/
algorithms.cpp, class Sac, on Table 6's 3 x 256 MLPs and a state of 80):
the C++ side is `manibench_learning_bench --algorithm sac`, the twin the
same update written the usual PyTorch way (critics frozen while the actor
steps, as the C++ does).

  python3 bench/learning_speed.py --cxx build/bin/manibench_learning_bench
  python3 bench/learning_speed.py --nets sac:1024 --threads 1
"""
import argparse
import os
import subprocess
import sys
import time


def parse():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--cxx", default="build/bin/manibench_learning_bench")
    p.add_argument("--nets", default="mlp:1024,mlp:128,pointnet:128,pn_transformer:128",
                   help="net:batch pairs")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--seconds", type=float, default=20)
    p.add_argument("--pairs", type=int, default=3)
    p.add_argument("--definition", action="store_true", help="the C++ side without its fast PointNet")
    p.add_argument("--python-only", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--net", help=argparse.SUPPRESS)
    p.add_argument("--batch", type=int, help=argparse.SUPPRESS)
    return p.parse_args()


def time_calls(update, seconds):
    """(calls, seconds) of `update` for `seconds`, at least 3, after two untimed."""
    for _ in range(2):
        update()
    iterations, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds or iterations < 3:
        update()
        iterations += 1
    return iterations, time.perf_counter() - start


def make_layers():
    """The twins' layers, as learning/src/networks.cpp initializes them:
    linear(i, o) (Xavier-uniform weights, zero bias) and Mlp(i, layers,
    activate_last) (ReLU between layers). Imported here, not at the top:
    the parent process runs without torch."""
    import torch
    from torch import nn

    def linear(i, o):
        layer = nn.Linear(i, o)
        nn.init.xavier_uniform_(layer.weight)
        nn.init.zeros_(layer.bias)
        return layer

    class Mlp(nn.Module):
        def __init__(self, i, layers, activate_last):
            super().__init__()
            self.layers = nn.ModuleList()
            for o in layers:
                self.layers.append(linear(i, o))
                i = o
            self.activate_last = activate_last

        def forward(self, x):
            for k, layer in enumerate(self.layers):
                x = layer(x)
                if k + 1 < len(self.layers) or self.activate_last:
                    x = torch.relu(x)
            return x

    return linear, Mlp


def run_python(net, batch, threads, seconds):
    """One measurement in this process (called in a child, see main)."""
    import torch
    from torch import nn
    torch.set_num_threads(threads)
    torch.manual_seed(0)

    linear, Mlp = make_layers()

    def pool(f, mask):
        half = f.shape[-1] // 2
        m = mask.unsqueeze(-1)
        count = mask.sum(1, keepdim=True)
        mx = f[..., :half].masked_fill(m == 0, float("-inf")).amax(1)
        mx = torch.where(count > 0, mx, torch.zeros_like(mx))
        mean = (f[..., half:] * m).sum(1) / count.clamp(min=1)
        return torch.cat([mx, mean], -1)

    class PointNet(nn.Module):
        def __init__(self, masks, state, layers, activate_last):
            super().__init__()
            self.mlp = Mlp(3 + 3 + masks + 3 + state, layers, activate_last)

        def forward(self, xyz, rgb, seg, state, mask):
            m = mask.unsqueeze(-1)
            mean = (xyz * m).sum(1, keepdim=True) / m.sum(1, keepdim=True).clamp(min=1)
            f = torch.cat([xyz - mean, rgb, seg, mean.expand_as(xyz),
                           state.unsqueeze(1).expand(-1, xyz.shape[1], -1)], -1)
            return pool(self.mlp(f), mask)

    class Attention(nn.Module):
        def __init__(self, w, heads, d, dropout):
            super().__init__()
            self.q, self.k, self.v = linear(w, heads * d), linear(w, heads * d), linear(w, heads * d)
            self.out = linear(heads * d, w)
            self.heads, self.d = heads, d
            self.dropout = nn.Dropout(dropout)

        def forward(self, x, mask):
            b, t, _ = x.shape
            split = lambda y: y.view(b, t, self.heads, self.d).transpose(1, 2)
            q, k, v = split(self.q(x)), split(self.k(x)), split(self.v(x))
            s = (q @ k.transpose(-2, -1)) / self.d ** 0.5
            s = s.masked_fill(mask.unsqueeze(1) == 0, float("-inf"))
            a = self.dropout(torch.softmax(s, -1))
            return self.out((a @ v).transpose(1, 2).reshape(b, t, -1))

    class Block(nn.Module):
        def __init__(self, w=256, heads=4, d=32, ff=1024, dropout=0.1):
            super().__init__()
            self.attention = Attention(w, heads, d, dropout)
            self.mlp = Mlp(w, [ff, w], False)
            self.norm1, self.norm2 = nn.LayerNorm(w), nn.LayerNorm(w)
            self.dropout = nn.Dropout(dropout)

        def forward(self, x, mask):
            x = self.norm1(x + self.attention(x, mask))
            return self.norm2(x + self.dropout(self.mlp(x)))

    class Pooling(nn.Module):
        def __init__(self, w=256, heads=4, d=32):
            super().__init__()
            self.query = nn.Parameter(torch.empty(heads, d))
            nn.init.xavier_normal_(self.query)
            self.k, self.v, self.out = linear(w, heads * d), linear(w, heads * d), linear(heads * d, w)
            self.heads, self.d = heads, d

        def forward(self, x, mask):
            b, t, _ = x.shape
            k = self.k(x).view(b, t, self.heads, self.d)
            v = self.v(x).view(b, t, self.heads, self.d)
            s = (k * self.query).sum(-1) / self.d ** 0.5
            s = s.masked_fill(mask.unsqueeze(-1) == 0, float("-inf"))
            w = torch.softmax(s, 1).unsqueeze(-1)
            return self.out((w * v).sum(1).reshape(b, -1))

    class PnTransformer(nn.Module):
        def __init__(self, masks, state, out, w=256, layers=6):
            super().__init__()
            self.masks = masks
            # Without the mask channels, as manibench's (and ManiSkill-Learn's).
            self.pointnets = nn.ModuleList([PointNet(0, state, [w, w], False) for _ in range(masks + 2)])
            self.globals = nn.ModuleList([Mlp(w, [w, w], False) for _ in range(masks + 2)])
            self.state_mlp = Mlp(state, [w, w], False)
            self.task = nn.Parameter(torch.empty(1, 1, w))
            nn.init.xavier_normal_(self.task)
            self.blocks = nn.ModuleList([Block(w) for _ in range(layers)])
            self.pooling = Pooling(w)
            self.head = Mlp(w, [128, out], False)

        def forward(self, obs):
            b = obs["state"].shape[0]
            valid, seg = obs["valid"], obs["seg"]
            some = (seg.sum(-1) > 0.5).float()
            masks = [valid * (1 - some)] + [seg[..., j] * valid for j in range(self.masks)] + [valid]
            tokens = [self.state_mlp(obs["state"])]
            present = [torch.ones(b)]
            for i, m in enumerate(masks):
                tokens.append(self.globals[i](self.pointnets[i](obs["xyz"], obs["rgb"], seg[..., :0], obs["state"], m)))
                present.append((m.sum(1) > 0).float())
            x = torch.cat([self.task.expand(b, 1, -1), torch.stack(tokens, 1)], 1)
            p = torch.stack(present, 1)
            mask = p.unsqueeze(2) * p.unsqueeze(1)
            mask = torch.cat([torch.ones(b, 1, mask.shape[2]), mask], 1)
            mask = torch.cat([torch.ones(b, mask.shape[1], 1), mask], 2)
            for block in self.blocks:
                x = block(x, mask)
            return self.head(self.pooling(x, mask[:, -1]))

    class VanillaPointNet(nn.Module):
        def __init__(self, masks, state, out):
            super().__init__()
            self.pointnet = PointNet(masks, state, [256, 512], True)
            self.head = Mlp(512, [256, out], False)

        def forward(self, obs):
            return self.head(self.pointnet(obs["xyz"], obs["rgb"], obs["seg"], obs["state"], obs["valid"]))

    class StateMlp(nn.Module):
        def __init__(self, state, out):
            super().__init__()
            self.mlp = Mlp(state, [256, 256, 256, out], False)

        def forward(self, obs):
            return self.mlp(obs["state"])

    def make_batch(cloud, n):
        obs = {"state": torch.randn(n, 51 if cloud else 80)}
        if cloud:
            obs["xyz"], obs["rgb"] = torch.rand(n, 1200, 3), torch.rand(n, 1200, 3)
            seg = torch.zeros(n, 1200, 3)
            seg[:, 0:100, 0] = 1
            seg[:, 0:400, 1] = 1
            seg[:, 400:800, 2] = 1
            obs["seg"], obs["valid"] = seg, torch.ones(n, 1200)
        return obs

    cloud = net != "mlp"
    model = {"mlp": lambda: StateMlp(80, 11), "pointnet": lambda: VanillaPointNet(3, 51, 11),
             "pn_transformer": lambda: PnTransformer(3, 51, 11)}[net]()
    # manibench's BC defaults for the mode (AlgorithmOptions::makeDefaults).
    optimizer = torch.optim.Adam(model.parameters(), lr=3e-4 if cloud else 1e-3, weight_decay=5e-6 if cloud else 0)
    obs, actions = make_batch(cloud, batch), torch.rand(batch, 11) * 2 - 1

    def update():
        model.train()
        loss = torch.nn.functional.mse_loss(torch.tanh(model(obs)), actions)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        return loss.item()

    iterations, elapsed = time_calls(update, seconds)
    one = make_batch(cloud, 1)
    model.eval()
    with torch.no_grad():
        for _ in range(3):
            torch.tanh(model(one))
        acts, act_start = 0, time.perf_counter()
        while time.perf_counter() - act_start < min(5.0, seconds) or acts < 10:
            torch.tanh(model(one))
            acts += 1
        act_elapsed = time.perf_counter() - act_start
    parameters = sum(p.numel() for p in model.parameters())
    print(f"python3-torch {net} batch {batch} threads {threads}: {iterations / elapsed:.3f} it/s "
          f"({iterations} iterations in {elapsed:.1f} s), act {1e3 * act_elapsed / acts:.3f} ms, "
          f"{parameters} parameters")


def run_python_sac(batch, threads, seconds):
    """SAC's update (learning/src/algorithms.cpp, Sac::update) in PyTorch."""
    import math
    import torch
    from torch import nn
    torch.set_num_threads(threads)
    torch.manual_seed(0)
    state_dim, action_dim = 80, 11

    _, Mlp = make_layers()

    class Net(nn.Module):
        # The C++ networks normalize the state with stored buffers first.
        def __init__(self, extra, out):
            super().__init__()
            self.register_buffer("mean", torch.zeros(state_dim))
            self.register_buffer("scale", torch.ones(state_dim))
            self.mlp = Mlp(state_dim + extra, [256, 256, 256, out], False)

        def forward(self, state, extra=None):
            s = (state - self.mean) * self.scale
            return self.mlp(s if extra is None else torch.cat([s, extra], 1))

    actor = Net(0, 2 * action_dim)
    critics = [Net(action_dim, 1), Net(action_dim, 1)]
    targets = [Net(action_dim, 1), Net(action_dim, 1)]
    for t, c in zip(targets, critics):
        t.load_state_dict(c.state_dict())
    actor_opt = torch.optim.Adam(actor.parameters(), lr=3e-4)
    critic_opt = torch.optim.Adam([p for c in critics for p in c.parameters()], lr=3e-4)
    log_temperature = torch.full((1,), math.log(0.2), requires_grad=True)
    temperature_opt = torch.optim.Adam([log_temperature], lr=3e-4)
    target_entropy = -1.0 * action_dim

    obs, next_obs = torch.randn(batch, state_dim), torch.randn(batch, state_dim)
    actions = torch.rand(batch, action_dim) * 2 - 1
    rewards, dones = torch.randn(batch), (torch.rand(batch) < 0.01).float()

    def sample(state):
        out = actor(state)
        mean, log_std = out[:, :action_dim], out[:, action_dim:].clamp(-20, 2)
        noise = torch.randn_like(mean)
        u = mean + log_std.exp() * noise
        log_prob = (-0.5 * noise.pow(2) - log_std - 0.5 * math.log(2 * math.pi)).sum(1) - \
            (2 * (math.log(2.0) - u - nn.functional.softplus(-2 * u))).sum(1)
        return torch.tanh(u), log_prob

    def step(optimizer, loss):
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()

    def update():
        for net in [actor] + critics + targets:
            net.train()
        temperature = log_temperature.exp().detach()
        with torch.no_grad():
            next_action, next_log_prob = sample(next_obs)
            q_next = torch.min(targets[0](next_obs, next_action), targets[1](next_obs, next_action)).squeeze(1)
            target = rewards + 0.95 * (1 - dones) * (q_next - temperature * next_log_prob)
        critic_loss = sum(nn.functional.mse_loss(c(obs, actions).squeeze(1), target) for c in critics)
        step(critic_opt, critic_loss)
        for c in critics:
            c.requires_grad_(False)
        action, log_prob = sample(obs)
        q = torch.min(critics[0](obs, action), critics[1](obs, action)).squeeze(1)
        actor_loss = (temperature * log_prob - q).mean()
        step(actor_opt, actor_loss)
        for c in critics:
            c.requires_grad_(True)
        step(temperature_opt, -(log_temperature * (log_prob.detach() + target_entropy)).mean())
        with torch.no_grad():
            for t, c in zip(targets, critics):
                for pt, pc in zip(t.parameters(), c.parameters()):
                    pt.mul_(1 - 0.005).add_(pc, alpha=0.005)
        return [critic_loss.item(), actor_loss.item(), temperature.item(), -log_prob.mean().item(), q.mean().item()]

    iterations, elapsed = time_calls(update, seconds)
    print(f"python3-torch sac batch {batch} threads {threads}: {iterations / elapsed:.3f} updates/s")


def measure(command, env):
    done = subprocess.run(command, env=env, capture_output=True, text=True)
    if done.returncode != 0:
        # A failed side names itself and its own error (e.g. a python3 without
        # torch: Debian's python3-torch is /usr/bin/python3's).
        sys.exit(f"learning_speed.py: {' '.join(command)} failed ({done.returncode}):\n{done.stderr.strip()}")
    out = done.stdout.strip().splitlines()[-1]
    rate = float(out.split(": ")[1].split(" ")[0])
    act = float(out.split("act ")[1].split(" ms")[0]) if "act " in out else float("nan")
    return rate, act, out


def main():
    args = parse()
    if args.python_only:
        if args.net == "sac":
            run_python_sac(args.batch, args.threads, args.seconds)
        else:
            run_python(args.net, args.batch, args.threads, args.seconds)
        return
    env = dict(os.environ, OPENBLAS_NUM_THREADS=str(args.threads), OMP_NUM_THREADS=str(args.threads))
    rows = []
    for spec in args.nets.split(","):
        net, batch = spec.split(":")
        cxx = [args.cxx, "--net", net, "--batch", batch, "--threads", str(args.threads),
               "--seconds", str(args.seconds)] + (["--definition"] if args.definition else [])
        if net == "sac":
            cxx = [args.cxx, "--algorithm", "sac", "--batch", batch, "--threads", str(args.threads),
                   "--seconds", str(args.seconds), "--pairs", "0"]
        py = [sys.executable, __file__, "--python-only", "--net", net, "--batch", batch,
              "--threads", str(args.threads), "--seconds", str(args.seconds)]
        results = {"manibench": [], "python3-torch": []}
        for pair in range(args.pairs):
            for name, command in (("manibench", cxx), ("python3-torch", py)):
                rate, act, line = measure(command, env)
                results[name].append((rate, act))
                print(line, flush=True)
        rows.append((net, batch, results))
    print(f"\n{'network':16} {'batch':>5} {'manibench it/s':>15} {'python3-torch it/s':>19} {'ratio':>6} "
          f"{'act ms (mb / py)':>17}")
    for net, batch, r in rows:
        med = lambda xs: sorted(xs)[len(xs) // 2]
        a, b = med([x[0] for x in r["manibench"]]), med([x[0] for x in r["python3-torch"]])
        la, lb = med([x[1] for x in r["manibench"]]), med([x[1] for x in r["python3-torch"]])
        print(f"{net:16} {batch:>5} {a:15.2f} {b:19.2f} {a / b:6.2f} {la:8.2f} / {lb:6.2f}")


if __name__ == "__main__":
    main()
