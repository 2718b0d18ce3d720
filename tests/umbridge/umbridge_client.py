#!/usr/bin/env python3
"""UM-Bridge protocol client test for systole (docs/umbridge.md).

Starts a real systole-server with one local worker and its UM-Bridge endpoint on an ephemeral
port, then talks to it as a UQ tool would, with a small client written against the published
UM-Bridge 1.0 protocol (HTTP + JSON; only python3-requests): every endpoint, the default and a
custom input/output mapping, shared jobs for identical points, and each documented error type.
If python3-openturns is installed, the model is also wrapped as an ot.PythonFunction and a
small Latin hypercube sample is evaluated through it; without OpenTURNS that part is skipped.

Exit status: 0 passed, 1 failed, 77 skipped (python3-requests missing).
"""
import argparse
import concurrent.futures
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

try:
    import requests
except ImportError:
    print("SKIP: python3-requests is not installed (apt-get install python3-requests)")
    sys.exit(77)


class UmBridgeError(Exception):
    """An error answer: {"error": {"type": ..., "message": ...}} with its HTTP status."""

    def __init__(self, status, kind, message):
        super().__init__(f"{kind} (HTTP {status}): {message}")
        self.status = status
        self.kind = kind
        self.message = message


class HttpModel:
    """A UM-Bridge 1.0 model over HTTP, written from the protocol description."""

    def __init__(self, url, name="forward", timeout_s=300):
        self.url = url.rstrip("/")
        self.name = name
        self.timeout_s = timeout_s
        self.last_headers = {}

    def _answer(self, response):
        self.last_headers = response.headers
        try:
            body = response.json()
        except ValueError:
            raise AssertionError(f"HTTP {response.status_code}: not JSON: {response.text[:200]!r}")
        if "error" in body:
            error = body["error"]
            raise UmBridgeError(response.status_code, error.get("type"), error.get("message"))
        if response.status_code != 200:
            raise AssertionError(f"HTTP {response.status_code} without an error body: {body}")
        return body

    def post(self, endpoint, body):
        return self._answer(requests.post(self.url + endpoint, json=body, timeout=self.timeout_s))

    def info(self):
        return self._answer(requests.get(self.url + "/Info", timeout=self.timeout_s))

    def model_info(self):
        return self.post("/ModelInfo", {"name": self.name})["support"]

    def input_sizes(self, config=None):
        return self.post("/InputSizes", {"name": self.name, "config": config or {}})["inputSizes"]

    def output_sizes(self, config=None):
        return self.post("/OutputSizes", {"name": self.name, "config": config or {}})["outputSizes"]

    def __call__(self, parameters, config=None):
        return self.post("/Evaluate", {"name": self.name, "input": parameters, "config": config or {}})["output"]


def check(condition, message):
    if not condition:
        raise AssertionError(message)


def expect_error(call, kind, status, needle=""):
    """Runs call(); it must fail with this error type, HTTP status and message fragment."""
    try:
        call()
    except UmBridgeError as e:
        check(e.kind == kind and e.status == status and needle in e.message,
              f"expected {kind}/{status} mentioning {needle!r}, got {e}")
        return e
    raise AssertionError(f"expected a {kind} error, the call succeeded")


class Server:
    def __init__(self, server_binary, worker_binary, work_dir):
        self.dir = work_dir
        self.log_path = os.path.join(work_dir, "server.log")
        ports = os.path.join(work_dir, "ports.json")
        env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
        args = [server_binary, "--listen", "127.0.0.1:0", "--http-listen", "127.0.0.1:0",
                "--umbridge-listen", "127.0.0.1:0", "--db", os.path.join(work_dir, "systole.db"),
                "--data-dir", os.path.join(work_dir, "data"), "--port-file", ports,
                "--local-workers", "1", "--lease-ms", "4000"]
        if worker_binary:
            args += ["--worker-binary", worker_binary]
        self.log = open(self.log_path, "w")
        self.process = subprocess.Popen(args, stdout=self.log, stderr=subprocess.STDOUT, env=env)
        deadline = time.time() + 30
        while not os.path.exists(ports):
            if self.process.poll() is not None or time.time() > deadline:
                raise AssertionError("systole-server did not start:\n" + self.tail())
            time.sleep(0.05)
        with open(ports) as f:
            self.ports = json.load(f)
        check(self.ports.get("umbridge"), f"the port file has no UM-Bridge port: {self.ports}")
        self.umbridge_url = f"http://127.0.0.1:{self.ports['umbridge']}"
        self.rest_url = f"http://127.0.0.1:{self.ports['http']}"

    def tail(self, lines=40):
        with open(self.log_path) as f:
            return "".join(f.readlines()[-lines:])

    def stop(self):
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.log.close()
        return self.process.returncode


DEFAULT_INPUTS = ["lumped.lv.emax_mmhg_per_ml", "heart_rate_bpm", "lumped.systemic_resistance_mmhg_s_per_ml"]
NOMINAL = [2.7, 70.0, 1.05]


def test_protocol(model, server):
    info = model.info()
    check(info["protocolVersion"] == 1.0, f"protocolVersion {info}")
    check(info["models"] == ["forward"], f"models {info}")
    support = model.model_info()
    check(support == {"Evaluate": True, "Gradient": False, "ApplyJacobian": False, "ApplyHessian": False},
          f"support {support}")
    check(model.input_sizes() == [3] and model.output_sizes() == [2], "default sizes")
    custom = {"inputs": ["heart_rate_bpm"], "outputs": ["heart_rate_bpm", "stroke_volume_ml", "edv_ml"]}
    check(model.input_sizes(custom) == [1] and model.output_sizes(custom) == [3], "custom sizes")
    print("ok   Info, ModelInfo, InputSizes, OutputSizes")

    # The default model at the healthy adult's nominal values: a physiological EF and CO.
    t0 = time.time()
    [[ef, co]] = model([NOMINAL])
    first_job = model.last_headers.get("X-Systole-Job-Id")
    check(45 < ef < 75, f"EF {ef} % at the nominal point")
    check(3.5 < co < 7.5, f"CO {co} l/min at the nominal point")
    check(first_job, "no X-Systole-Job-Id header")
    print(f"ok   Evaluate {NOMINAL} -> EF {ef:.2f} %, CO {co:.3f} l/min (job {first_job}, {time.time() - t0:.2f} s)")
    # The same point again: the same job, the same answer.
    check(model([NOMINAL]) == [[ef, co]], "a repeated Evaluate changed its answer")
    check(model.last_headers.get("X-Systole-Job-Id") == first_job, "a repeated Evaluate ran a new job")
    # The job is an ordinary job of the service.
    job = requests.get(f"{server.rest_url}/v1/jobs/{first_job}", timeout=30).json()
    check(job["state"] == "SUCCEEDED" and job["scene"] == "lumped", f"job {job}")
    # A stiffer ventricle ejects more.
    [[ef_weak, _]] = model([[1.5, 70.0, 1.05]])
    [[ef_strong, _]] = model([[4.0, 70.0, 1.05]])
    check(ef_weak < ef < ef_strong, f"EF should grow with LV elastance: {ef_weak}, {ef}, {ef_strong}")
    print(f"ok   EF grows with Emax: {ef_weak:.1f} < {ef:.1f} < {ef_strong:.1f} %")
    # Custom mapping: order as configured; the heart rate metric echoes the input.
    [[hr, sv, edv]] = model([[80.0]], custom)
    check(hr == 80.0 and 20 < sv < edv, f"custom outputs {hr}, {sv}, {edv}")
    print(f"ok   custom config: heart_rate_bpm 80 -> [{hr}, {sv:.1f}, {edv:.1f}]")

    # Several clients asking for the same new point share one job.
    point = [[2.9, 75.0, 1.0]]
    with concurrent.futures.ThreadPoolExecutor(4) as pool:
        def one(_):
            client = HttpModel(model.url)
            out = client(point)
            return out, client.last_headers.get("X-Systole-Job-Id")
        answers = list(pool.map(one, range(4)))
    check(len({a[1] for a in answers}) == 1 and all(a[0] == answers[0][0] for a in answers),
          f"concurrent identical Evaluates did not share one job: {answers}")
    print(f"ok   4 concurrent identical Evaluates -> one job ({answers[0][1]})")


def test_errors(model, server):
    other = HttpModel(model.url, name="backward")
    expect_error(other.model_info, "ModelNotFound", 400, "backward")
    expect_error(other.input_sizes, "ModelNotFound", 400, "backward")
    expect_error(lambda: other([NOMINAL]), "ModelNotFound", 400, "backward")
    for feature in ("/Gradient", "/ApplyJacobian", "/ApplyHessian"):
        expect_error(lambda: model.post(feature, {"name": "forward", "inWrt": 0, "outWrt": 0, "input": [NOMINAL],
                                                  "sens": [1.0, 0.0], "vec": [1.0, 0.0, 0.0]}),
                     "UnsupportedFeature", 400, feature[1:])
    expect_error(lambda: model([[2.7, 70.0]]), "InvalidInput", 400, "expected 3")
    expect_error(lambda: model([NOMINAL, NOMINAL]), "InvalidInput", 400, "2 vectors")
    expect_error(lambda: model([[1.0]], {"inputs": ["lumped.lv.elastance"]}), "InvalidInput", 400,
                 "lumped.lv.elastance")
    expect_error(lambda: model([[30.0]], {"inputs": ["beats"]}), "InvalidInput", 400, "beats")
    expect_error(lambda: model([[1000.0, 70.0, 1.05]]), "InvalidInput", 400, "lumped.lv.emax_mmhg_per_ml")
    expect_error(lambda: model([NOMINAL], {"solver": "fast"}), "InvalidInput", 400, "solver")
    e = expect_error(lambda: model([NOMINAL], {"outputs": ["ejection_fraction_percent", "qrs_width_ms"]}),
                     "InvalidInput", 400, "qrs_width_ms")
    check("cardiac_output_l_min" in e.message, "the error should list the metrics the scene reports")
    # A point where the solver is unstable: the failed job is reported as this input's fault,
    # naming the job and the diagnosis; the service carries on.
    unstable = {"inputs": ["lumped.mitral_resistance_mmhg_s_per_ml"],
                "base_scenario": {"scene": "lumped",
                                  "lumped": {"time_step_ms": 5, "aortic_resistance_mmhg_s_per_ml": 0.0001}}}
    e = expect_error(lambda: model([[0.0001]], unstable), "InvalidInput", 400, "unstable")
    check(model.last_headers.get("X-Systole-Job-Id", "") in e.message, "the error should name the job")
    print("ok   ModelNotFound, UnsupportedFeature, InvalidInput (size, field, range, key, metric, unstable point)")

    # A slow job and a short timeout: a Timeout naming the job, which keeps running.
    slow = {"base_scenario": {"scene": "lumped", "beats": 500, "periodicity_tolerance": 0,
                              "lumped": {"time_step_ms": 0.002}},
            "timeout_s": 0.5}
    e = expect_error(lambda: model([NOMINAL], slow), "Timeout", 504, "did not finish within 0.5 s")
    job_id = model.last_headers.get("X-Systole-Job-Id")
    check(job_id and job_id in e.message, f"the timeout should name the job: {e.message}")
    # Free the worker: cancel the slow job through the REST API, then wait for it.
    requests.post(f"{server.rest_url}/v1/jobs/{job_id}:cancel", timeout=30)
    deadline = time.time() + 120
    while requests.get(f"{server.rest_url}/v1/jobs/{job_id}", timeout=30).json()["state"] != "CANCELLED":
        check(time.time() < deadline, f"job {job_id} was not cancelled")
        time.sleep(0.2)
    # Asking for that point again now: its job was CANCELLED, so a fresh job runs.
    e = expect_error(lambda: model([NOMINAL], dict(slow, timeout_s=0.3)), "Timeout", 504, "")
    second = model.last_headers.get("X-Systole-Job-Id")
    check(second and second != job_id, "a cancelled point should get a fresh job")
    requests.post(f"{server.rest_url}/v1/jobs/{second}:cancel", timeout=30)
    while requests.get(f"{server.rest_url}/v1/jobs/{second}", timeout=30).json()["state"] != "CANCELLED":
        check(time.time() < deadline, f"job {second} was not cancelled")
        time.sleep(0.2)
    print(f"ok   Timeout names the job ({job_id}); a cancelled point gets a new job ({second})")


def test_openturns(model):
    try:
        import openturns as ot
    except ImportError:
        print("SKIP openturns part: python3-openturns is not installed")
        return
    f = ot.PythonFunction(3, 2, lambda x: model([list(x)])[0])
    f.setInputDescription(DEFAULT_INPUTS)
    f.setOutputDescription(["ejection_fraction_percent", "cardiac_output_l_min"])
    inputs = ot.ComposedDistribution([ot.Uniform(1.8, 3.6), ot.Uniform(55.0, 95.0), ot.Uniform(0.85, 1.25)])
    ot.RandomGenerator.SetSeed(7)
    design = ot.LHSExperiment(inputs, 20).generate()
    t0 = time.time()
    outputs = f(design)
    elapsed = time.time() - t0
    check(outputs.getSize() == 20 and outputs.getDimension() == 2, "OpenTURNS output shape")
    for i in range(outputs.getSize()):
        ef, co = outputs[i, 0], outputs[i, 1]
        check(15 < ef < 95 and 1 < co < 12, f"sample {i} {list(design[i])}: EF {ef}, CO {co}")
    # EF is driven by the contractility: strongly correlated with Emax over this range.
    rho = pearson([design[i, 0] for i in range(20)], [outputs[i, 0] for i in range(20)])
    check(rho > 0.5, f"corr(Emax, EF) = {rho}")
    mean = outputs.computeMean()
    print(f"ok   OpenTURNS {ot.__version__}: PythonFunction over an LHS of 20 points in {elapsed:.1f} s; "
          f"mean EF {mean[0]:.1f} %, mean CO {mean[1]:.2f} l/min, corr(Emax, EF) {rho:.2f}")


def pearson(x, y):
    n = len(x)
    mx, my = sum(x) / n, sum(y) / n
    sxy = sum((a - mx) * (b - my) for a, b in zip(x, y))
    sxx = sum((a - mx) ** 2 for a in x)
    syy = sum((b - my) ** 2 for b in y)
    return sxy / (sxx * syy) ** 0.5


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--server-binary", required=True)
    parser.add_argument("--worker-binary", default="")
    parser.add_argument("--keep", action="store_true", help="keep the work directory")
    args = parser.parse_args()
    work_dir = tempfile.mkdtemp(prefix="systole-umbridge-client-")
    server = None
    ok = False
    try:
        server = Server(args.server_binary, args.worker_binary, work_dir)
        model = HttpModel(server.umbridge_url)
        print(f"systole-server: UM-Bridge {server.umbridge_url}, REST {server.rest_url}")
        test_protocol(model, server)
        test_errors(model, server)
        test_openturns(model)
        ok = True
    except AssertionError as e:
        print(f"FAIL {e}")
    finally:
        if server is not None:
            code = server.stop()
            if code != 0:
                print(f"FAIL systole-server exited with {code}")
                ok = False
            if not ok:
                print("--- server log (tail) ---\n" + server.tail())
        if ok and not args.keep:
            shutil.rmtree(work_dir, ignore_errors=True)
        else:
            print(f"work directory kept: {work_dir}")
    print("PASS" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
