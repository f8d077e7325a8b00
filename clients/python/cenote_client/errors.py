"""errors.py: CenoteError, the one exception a failed call raises.

code is the gRPC status code's name ("UNAUTHENTICATED", "INVALID_ARGUMENT", ...), message the
server's text, which names what was wrong. Bad shapes of arguments are caught before any call and
raise ValueError instead.
"""

import grpc


class CenoteError(Exception):
    def __init__(self, code, message, method=""):
        self.code = code
        self.message = message
        self.method = method
        where = f" ({method})" if method else ""
        super().__init__(f"{code}: {message}{where}")


def from_rpc_error(error, method=""):
    """CenoteError from a grpc.RpcError (a call's failure or a stream's)."""
    code = error.code() if hasattr(error, "code") else None
    details = error.details() if hasattr(error, "details") else str(error)
    name = code.name if isinstance(code, grpc.StatusCode) else "UNKNOWN"
    return CenoteError(name, details or "", method)


def status_name(code_number):
    """Name of a numeric grpc status code as carried in acks (status_code fields)."""
    for code in grpc.StatusCode:
        if code.value[0] == code_number:
            return code.name
    return f"STATUS_{code_number}"
