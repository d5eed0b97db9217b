"""The cgaskin test suite; its folders mirror the package's subpackages."""
