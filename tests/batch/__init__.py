"""Tests of cgaskin.batch (datasets on Dask)."""
