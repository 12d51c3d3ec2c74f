"""The data collector, the sink protocol it publishes to, and the trace file format."""

from rei.runtime.collector.collector import DataCollector
from rei.runtime.collector.config import MonitorConfig, load_monitor_config
from rei.runtime.collector.sink import SampleList, SampleSink
from rei.runtime.collector.trace import TraceError, TraceWriter, read_trace, write

__all__ = ["DataCollector", "MonitorConfig", "SampleList", "SampleSink", "TraceError",
           "TraceWriter", "load_monitor_config", "read_trace", "write"]
