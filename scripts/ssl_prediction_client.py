#!/usr/bin/env python3
"""Reads ssl-predictor's predictions off the wire, as a team's own software would.

Joins the prediction group (FormationPrediction, 224.5.23.4:10040 by default, on 127.0.0.1),
decodes each message with the project's proto/formation_prediction.proto and prints, per
message, every robot's predicted position, radii and probability per horizon; or, with --csv,
writes the very lines `ssl-predictor --from-log` writes for the same frames, so the two can be
compared (or a team's tools read either).

Needs Debian's python3-protobuf and protoc (protobuf-compiler): the Python module is generated
from the .proto into a temporary directory at start, so the reader always matches the schema it
is given (--proto). A datagram that does not decode is counted and skipped; nothing stops the
client but --count, --duration or Ctrl-C.

As a module (import ssl_prediction_client, from scripts/ or an installed
share/ssl-formation/python): load_schema(proto_dir), join(group, port, interface), csv_rows(message)
and summary(message) are what a team's own tool needs; main() is the script.

  scripts/ssl-prediction-client.py                         # print, until Ctrl-C
  scripts/ssl-prediction-client.py --csv predictions.csv --duration 60
  scripts/ssl-prediction-client.py --group 224.5.23.4:10040 --interface 192.168.1.20
"""

import argparse
import csv
import decimal
import ipaddress
import os
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
import warnings

CSV_HEADER = [
    "t_capture", "frame", "robot_id", "step", "horizon_s", "state_index", "predicted_cell_x",
    "predicted_cell_y", "predicted_x_mm", "predicted_y_mm", "probability", "unseen",
    "centroid_cell_x", "centroid_cell_y", "centroid_probability", "formation_probability",
    "confidence", "model", "predicted_feed_x_mm", "predicted_feed_y_mm", "radius_50_mm",
    "radius_90_mm", "grid", "step_s",
]


# ---- numbers as the predictor writes them (C++ std::to_chars: the shortest text that reads back
# as the same value; fixed or scientific, whichever is shorter, fixed on a tie)

def _layout(negative, digits, exponent):
    """The shorter of fixed and scientific text for the value int(digits) x 10^exponent."""
    if digits == "0":
        return "-0" if negative else "0"
    if exponent >= 0:
        fixed = digits + "0" * exponent
    else:
        point = len(digits) + exponent
        fixed = (digits[:point] + "." + digits[point:]) if point > 0 else (
            "0." + "0" * (-point) + digits)
    power = exponent + len(digits) - 1
    mantissa = digits[0] + ("." + digits[1:] if len(digits) > 1 else "")
    scientific = "%se%s%02d" % (mantissa, "+" if power >= 0 else "-", abs(power))
    text = fixed if len(fixed) <= len(scientific) else scientific
    return "-" + text if negative else text


def _from_decimal_text(text):
    sign, digit_tuple, exponent = decimal.Decimal(text).normalize().as_tuple()
    digits = "".join(str(d) for d in digit_tuple) or "0"
    return _layout(sign == 1, digits, exponent)


def shortest_double(value):
    return _from_decimal_text(repr(float(value)))


def _as_float32(value):
    return struct.unpack("<f", struct.pack("<f", value))[0]


def shortest_float(value):
    """A float32 field (protobuf hands it over widened to a double) in its shortest exact text."""
    value = float(value)
    if value == 0.0:
        return "-0" if str(value).startswith("-") else "0"
    for precision in range(1, 10):
        text = "%.*e" % (precision - 1, value)
        if _as_float32(float(text)) == value:
            return _from_decimal_text(text)
    return shortest_double(value)


# ---- the schema

def load_schema(proto_dir):
    """Generates formation_prediction_pb2 from the .proto and imports it."""
    proto = os.path.join(proto_dir, "formation_prediction.proto")
    if not os.path.isfile(proto):
        sys.exit("error: no %s (give the project's proto directory with --proto)" % proto)
    protoc = shutil.which("protoc")
    if not protoc:
        sys.exit("error: protoc not found: install Debian's protobuf-compiler")
    out = tempfile.mkdtemp(prefix="ssl-prediction-client-")
    generated = subprocess.run([protoc, "-I", proto_dir, "--python_out=" + out, proto],
                               capture_output=True, text=True)
    if generated.returncode != 0:
        sys.exit("error: protoc could not compile %s: %s" % (proto, generated.stderr.strip()))
    sys.path.insert(0, out)
    try:
        import formation_prediction_pb2  # noqa: E402 (generated just above)
    except ImportError as e:
        sys.exit("error: %s cannot import protobuf's Python module (%s): install it for this "
                 "interpreter (Debian's python3-protobuf for /usr/bin/python3, or "
                 "'%s -m pip install protobuf' in a virtual environment), or run the client "
                 "with a Python that has it" % (sys.executable, e, sys.executable))
    finally:
        sys.path.remove(out)
        shutil.rmtree(out, ignore_errors=True)
    return formation_prediction_pb2


# ---- the wire

def parse_group(text):
    host, _, port = text.rpartition(":")
    try:
        address = ipaddress.IPv4Address(host)
        port_number = int(port)
    except ValueError:
        sys.exit("error: --group takes ADDRESS:PORT (e.g. 224.5.23.4:10040), not '%s'" % text)
    if not address.is_multicast or not 0 < port_number < 65536:
        sys.exit("error: --group %s is not a multicast group and port" % text)
    return str(address), port_number


def join(group, port, interface):
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    # Bound to the group, not to every address: only this group's datagrams on the port.
    sock.bind((group, port))
    membership = socket.inet_aton(group) + socket.inet_aton(interface)
    sock.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, membership)
    return sock


# ---- what a message says

def field(message, name, default=None):
    """A field's value if this schema has it and the message set it: a reader built against an
    older .proto lacks the fields appended since, and must keep working without them."""
    if name in message.DESCRIPTOR.fields_by_name and message.HasField(name):
        return getattr(message, name)
    return default


def csv_rows(message):
    """The lines ssl-predictor --from-log writes for this message's frame, as lists of fields."""
    rows = []
    step_seconds = field(message, "step_seconds", 0.0)
    for step in message.steps:
        for robot in step.robots:
            feed = field(robot, "position", robot.cell_centre)
            radius_50 = field(robot, "radius_50_mm")
            radius_90 = field(robot, "radius_90_mm")
            rows.append([
                shortest_double(message.t_capture), str(message.frame_number),
                str(robot.robot_id), str(step.step),
                shortest_double(float(step.step) * step_seconds),
                str(robot.state_index), str(robot.position_cell.x), str(robot.position_cell.y),
                shortest_float(robot.cell_centre.x), shortest_float(robot.cell_centre.y),
                shortest_double(robot.probability), "1" if robot.unseen else "0",
                str(step.centroid_cell.x), str(step.centroid_cell.y),
                shortest_double(step.centroid_probability),
                shortest_double(step.formation_probability), shortest_double(step.confidence),
                field(message, "model", ""), shortest_float(feed.x), shortest_float(feed.y),
                shortest_float(radius_50) if radius_50 is not None else "0",
                shortest_float(radius_90) if radius_90 is not None else "0",
                "%dx%d" % (field(message, "grid_length", 0), field(message, "grid_width", 0)),
                shortest_double(step_seconds),
            ])
    return rows


def summary(message):
    """One line per step: where each robot is predicted, its 90% radius and probability."""
    lines = []
    state = field(message, "game_state")
    state = " " + state if state else ""
    step_seconds = field(message, "step_seconds")
    for step in message.steps:
        horizon = field(step, "horizon_seconds",
                        step.step * step_seconds if step_seconds is not None else None)
        ahead = "+%.1fs" % horizon if horizon is not None else "step %d" % step.step
        robots = []
        for robot in step.robots:
            at = field(robot, "position", robot.cell_centre)
            radius = field(robot, "radius_90_mm")
            robots.append("r%d (%.0f,%.0f)%s p=%.2f" % (
                robot.robot_id, at.x, at.y, " r90=%.0f" % radius if radius is not None else "",
                robot.probability))
        lines.append("t=%.2f frame=%d%s %s p(formation)=%.3f: %s" % (
            message.t_capture, message.frame_number, state, ahead,
            step.formation_probability, ", ".join(robots)))
    return "\n".join(lines)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(
        description="Join ssl-predictor's prediction group and print or record what it says.")
    parser.add_argument("--group", default="224.5.23.4:10040",
                        help="the prediction group, ADDRESS:PORT (default: %(default)s)")
    parser.add_argument("--interface", default="127.0.0.1",
                        help="address of the interface to join on (default: %(default)s)")
    parser.add_argument("--proto", default=os.path.join(here, os.pardir, "proto"),
                        help="directory of formation_prediction.proto (default: the project's)")
    parser.add_argument("--csv", metavar="FILE",
                        help="write the lines ssl-predictor --from-log writes ('-': stdout)")
    parser.add_argument("--count", type=int, default=0,
                        help="stop after this many messages (0: no limit)")
    parser.add_argument("--duration", type=float, default=0.0,
                        help="stop after this many seconds (0: no limit)")
    options = parser.parse_args()
    if options.count < 0 or options.duration < 0:
        sys.exit("error: --count and --duration take 0 (no limit) or more")
    try:
        ipaddress.IPv4Address(options.interface)
    except ValueError:
        sys.exit("error: --interface takes this machine's IPv4 address, not '%s'"
                 % options.interface)

    schema = load_schema(os.path.normpath(options.proto))
    group, port = parse_group(options.group)
    sock = join(group, port, options.interface)
    print("listening on %s:%d (interface %s)" % (group, port, options.interface),
          file=sys.stderr, flush=True)

    out = None
    writer = None
    if options.csv:
        out = sys.stdout if options.csv == "-" else open(options.csv, "w", newline="")
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(CSV_HEADER)
        out.flush()

    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(True))
    signal.signal(signal.SIGINT, lambda *_: stop.append(True))
    deadline = time.monotonic() + options.duration if options.duration > 0 else None
    received = 0
    undecodable = 0
    sock.settimeout(0.2)
    while not stop:
        if deadline is not None and time.monotonic() >= deadline:
            break
        try:
            datagram = sock.recv(65536)
        except socket.timeout:
            continue
        except InterruptedError:
            continue
        message = schema.FormationPrediction()
        try:
            with warnings.catch_warnings():
                # Some protobuf versions warn, rather than fail, on bytes that are no message.
                warnings.simplefilter("ignore")
                message.ParseFromString(datagram)
        except Exception:  # a datagram that is not a FormationPrediction: counted, skipped
            undecodable += 1
            continue
        if not message.IsInitialized():
            # Python's parser does not check proto2's required fields: bytes that happen to
            # parse (even none at all) lack them.
            undecodable += 1
            continue
        received += 1
        if writer:
            writer.writerows(csv_rows(message))
            out.flush()
        else:
            print(summary(message), flush=True)
        if options.count and received >= options.count:
            break
    if out and out is not sys.stdout:
        out.close()
    print("%d predictions received, %d datagrams that did not decode" % (received, undecodable),
          file=sys.stderr, flush=True)


if __name__ == "__main__":
    main()
