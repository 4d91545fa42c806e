#!/usr/bin/env python3
"""OME-Zarr stores in S3 buckets of a local moto server (its signature checks on), read by
s3:// and https-style URLs.

  s3_moto_cli.py VOLVIS OUTDIR

Run with the .venv of scripts/install-deps.sh test (vv_pypi_test; moto[server] pinned).
moto's S3 runs in server mode on a free loopback port with INITIAL_NO_AUTH_ACTION_COUNT
set, so that once a user, its policy and its access key are made every request must be
signed with that key (SigV4, checked by moto). zarr-python 3 writes a sharded + zstd
NGFF 0.5 pyramid, boto3 puts it into a private bucket and into a public-read one.
Checked, with AWS_ENDPOINT_URL naming the server:

- the right key (from the environment, and from a profile of ~/.aws/credentials via
  AWS_PROFILE and AWS_SHARED_CREDENTIALS_FILE): `volvis info s3://BUCKET/store` is the
  local info but for the name; the render is the local PNG byte for byte;
- the path-style URL http://ENDPOINT/BUCKET/store reads alike;
- a wrong secret: one line naming the bucket (SignatureDoesNotMatch), no secret in it;
- no credentials (AWS_NO_SIGN_REQUEST=YES, requests unsigned): a public-read bucket renders.
  moto answers an unsigned request 500 once its signature checks are on (it looks for an
  Authorization header), so this runs against a second moto server without them;
- an absent store: one line naming it.
"""
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
try:
    import boto3
    import moto  # noqa: F401
    import zarr  # noqa: F401
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (bash scripts/install-deps.sh test makes .venv with moto[server])")
    sys.exit(77)
from http_common import free_port, setup, stop_server, wait_port  # noqa: E402

VOLVIS, OUT, check, www, v3, _ = setup(n=64)
port = free_port()
endpoint = f"http://127.0.0.1:{port}"
senv = dict(os.environ, INITIAL_NO_AUTH_ACTION_COUNT="4", MOTO_ALLOW_NONEXISTENT_REGION="1")
server = subprocess.Popen([sys.executable, "-m", "moto.server", "-H", "127.0.0.1", "-p",
                           str(port)], env=senv, stdout=subprocess.DEVNULL,
                          stderr=open(os.path.join(OUT, "moto.log"), "w"))
port2 = free_port()
endpoint2 = f"http://127.0.0.1:{port2}"
server2 = subprocess.Popen([sys.executable, "-m", "moto.server", "-H", "127.0.0.1", "-p",
                            str(port2)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
base = {k: v for k, v in os.environ.items()
        if not k.startswith("AWS_") and not k.lower().endswith("_proxy")}
base.update(AWS_ENDPOINT_URL=endpoint, AWS_REGION="us-east-1", HOME=OUT)


def volvis(*args, **env):
    e = dict(base, **env)
    return subprocess.run([VOLVIS, *args], capture_output=True, text=True, env=e, timeout=120)


def one_line(p, needles, what, secret=None):
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    ok = p.returncode != 0 and len(lines) == 1 and all(n in lines[0] for n in needles)
    if secret:
        ok = ok and secret not in p.stderr and secret not in p.stdout
    check(ok, f"{what}: one line naming {needles} ({lines[:3]}, exit {p.returncode})")


try:
    if not wait_port(port, server, 30) or not wait_port(port2, server2, 30):
        print("moto did not start:", open(os.path.join(OUT, "moto.log")).read()[-2000:])
        sys.exit(1)
    # the user, its policy and key: the four requests moto takes unsigned
    iam = boto3.client("iam", endpoint_url=endpoint, region_name="us-east-1",
                       aws_access_key_id="setup", aws_secret_access_key="setup")
    iam.create_user(UserName="viewer")
    pol = iam.create_policy(PolicyName="s3all", PolicyDocument='{"Version": "2012-10-17", '
                            '"Statement": [{"Effect": "Allow", "Action": "s3:*", '
                            '"Resource": "*"}]}')
    iam.attach_user_policy(UserName="viewer", PolicyArn=pol["Policy"]["Arn"])
    key = iam.create_access_key(UserName="viewer")["AccessKey"]
    kid, secret = key["AccessKeyId"], key["SecretAccessKey"]
    s3 = boto3.client("s3", endpoint_url=endpoint, region_name="us-east-1",
                      aws_access_key_id=kid, aws_secret_access_key=secret)
    s3.create_bucket(Bucket="private-zarr")
    pub = boto3.client("s3", endpoint_url=endpoint2, region_name="us-east-1",
                       aws_access_key_id="x", aws_secret_access_key="x")
    pub.create_bucket(Bucket="public-zarr", ACL="public-read")
    for root, _, files in os.walk(v3):
        for f in files:
            path = os.path.join(root, f)
            k = "store/" + os.path.relpath(path, v3)
            s3.upload_file(path, "private-zarr", k)
            pub.upload_file(path, "public-zarr", k, ExtraArgs={"ACL": "public-read"})
    # the signature is checked: a wrong secret is refused by moto itself
    bad = boto3.client("s3", endpoint_url=endpoint, region_name="us-east-1",
                       aws_access_key_id=kid, aws_secret_access_key="wrong" + secret[5:])
    try:
        bad.get_object(Bucket="private-zarr", Key="store/zarr.json")
        check(False, "moto checks signatures (a wrong secret read an object)")
    except Exception as e:  # botocore.exceptions.ClientError
        check("SignatureDoesNotMatch" in str(e), f"moto checks signatures ({e})")
    keys = dict(AWS_ACCESS_KEY_ID=kid, AWS_SECRET_ACCESS_KEY=secret)
    pl = volvis("info", v3)
    url = "s3://private-zarr/store"
    pu = volvis("info", url, **keys)
    check(pl.returncode == 0 and pu.returncode == 0 and pu.stdout.replace(url, v3) == pl.stdout,
          f"info s3:// with the right key equals the local info ({pu.stderr.strip()})")
    how = ["--size", "64x64", "--mode", "mip", "--tf", "50:1000"]
    a = os.path.join(OUT, "local.png")
    volvis("render", v3, "-o", a, *how)
    want = open(a, "rb").read()
    for name, u, env in (("s3:// env keys", url, keys),
                         ("path-style URL", f"{endpoint}/private-zarr/store", keys),
                         ("s3:// profile", url, None),
                         ("public bucket, anonymous", "s3://public-zarr/store",
                          {"AWS_NO_SIGN_REQUEST": "YES", "AWS_ENDPOINT_URL": endpoint2})):
        if env is None:
            cred = os.path.join(OUT, "credentials")
            with open(cred, "w") as f:
                f.write(f"[default]\naws_access_key_id = nobody\naws_secret_access_key = x\n"
                        f"[viewer]\naws_access_key_id = {kid}\n"
                        f"aws_secret_access_key = {secret}\n")
            env = {"AWS_PROFILE": "viewer", "AWS_SHARED_CREDENTIALS_FILE": cred}
        b = os.path.join(OUT, f"{name.replace(' ', '_').replace('/', '')}.png")
        t = time.monotonic()
        p = volvis("render", u, "-o", b, *how, **env)
        check(p.returncode == 0 and open(b, "rb").read() == want,
              f"render {name}: the local PNG byte for byte ({p.stderr.strip()}, "
              f"{time.monotonic() - t:.1f} s)")
    wrong = "wrongsecretwrongsecret"
    one_line(volvis("info", url, AWS_ACCESS_KEY_ID=kid, AWS_SECRET_ACCESS_KEY=wrong),
             ["private-zarr", "SignatureDoesNotMatch"], "a wrong secret", secret=wrong)
    one_line(volvis("info", "s3://private-zarr/none", **keys), ["s3://private-zarr/none"],
             "an absent store")
finally:
    for srv in (server, server2):
        stop_server(srv)
check.finish("s3_moto_cli")
