#!/usr/bin/env python3
"""The prediction client as a command: ssl_prediction_client.py beside it (the source tree) or
in ../share/ssl-formation/python (an installed prefix) does the work."""
import os
import sys

here = os.path.dirname(os.path.abspath(__file__))
for folder in (here, os.path.join(here, os.pardir, "share", "ssl-formation", "python")):
    if os.path.isfile(os.path.join(folder, "ssl_prediction_client.py")):
        sys.path.insert(0, os.path.normpath(folder))
        break
import ssl_prediction_client  # noqa: E402 (found just above)

# The first python3 on the PATH may lack protobuf where Debian's has it (a pyenv, a virtual
# environment without it): run under Debian's then, once; the module's error names the
# interpreter when neither has it.
try:
    import google.protobuf  # noqa: F401
except ImportError:
    system = "/usr/bin/python3"
    if (not os.environ.get("SSLF_CLIENT_REEXEC") and os.access(system, os.X_OK) and
            os.path.realpath(sys.executable) != os.path.realpath(system)):
        os.environ["SSLF_CLIENT_REEXEC"] = "1"
        os.execv(system, [system, os.path.abspath(__file__)] + sys.argv[1:])

if __name__ == "__main__":
    sys.exit(ssl_prediction_client.main())
