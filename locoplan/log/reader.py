"""Read locoplan MCAP logs, including files left by a killed process, and repair those.

A file closed properly has a summary (channel list, statistics, indexes) and is read through
its index. A file whose writer was killed ends in a half-written chunk and has no summary or
footer: it is read front to back and the reading stops at the first record that cannot be
parsed; everything before it (every chunk the writer flushed) is returned. `recover_log`
rewrites such a file into a complete, indexed one.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import struct
import tempfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import zstandard
from mcap.decoder import DecoderFactory as McapDecoderFactory
from mcap.exceptions import McapError
from mcap.reader import NonSeekingReader, SeekingReader
from mcap.records import (
    Attachment,
    Channel,
    DataEnd,
    Footer,
    Header,
    Message,
    Metadata,
    Schema,
)
from mcap.stream_reader import StreamReader
from mcap.writer import Writer
from mcap_protobuf.decoder import DecoderFactory as ProtobufDecoderFactory

from locoplan import __version__
from locoplan.exceptions import LocoplanError
from locoplan.log import topics

# What parsing a torn record can raise: mcap's own errors, bad opcodes/strings (ValueError),
# short reads (struct.error, EndOfFile), garbage chunk bodies (zstd) and seeks before the start
# of a file shorter than a footer (OSError).
_BROKEN = (McapError, ValueError, struct.error, EOFError, OSError, zstandard.ZstdError)

# A torn record's length field can hold anything; refuse to allocate more than this for one.
_RECORD_SIZE_LIMIT = 1 << 30


class LogReadError(LocoplanError):
    """A file is not an MCAP log (or not even its header can be read)."""

    def __init__(self, path: Path, detail: str) -> None:
        self.path = path
        self.detail = detail
        super().__init__(f"{path}: not a readable MCAP log: {detail}")


@dataclass(frozen=True, slots=True)
class TopicInfo:
    """One topic of a log: its schema and how many messages it holds."""

    topic: str
    schema_name: str
    schema_encoding: str
    message_encoding: str
    message_count: int


@dataclass(frozen=True, slots=True)
class RunLog:
    """What `read_log` found in a file.

    `complete` is False for a file without summary (its writer was killed); its contents are
    then those that survived. `metadata` maps record name (``locoplan``, ``metrics``,
    ``run_end``) to its key/values, `attachments` name to bytes. `start_time` / `end_time`
    are the first and last message log times (s of simulation time), None without messages.
    """

    path: Path
    complete: bool
    metadata: dict[str, dict[str, str]]
    attachments: dict[str, bytes]
    topics: dict[str, TopicInfo]
    start_time: float | None
    end_time: float | None

    @property
    def scenario_name(self) -> str | None:
        """The scenario name the writer stored, if the metadata survived."""
        return self.metadata.get(topics.METADATA_RUN, {}).get("scenario")

    @property
    def scenario_text(self) -> str | None:
        """The scenario YAML stored as attachment, if present."""
        data = self.attachments.get(topics.ATTACHMENT_SCENARIO)
        return None if data is None else data.decode("utf-8")

    @property
    def metrics(self) -> dict[str, Any] | None:
        """The final metrics (from ``metrics.json``), None if the run did not finish."""
        data = self.attachments.get(topics.ATTACHMENT_METRICS)
        return None if data is None else json.loads(data)

    def messages(self, topic: str) -> Iterator[tuple[float, Any]]:
        """Iterate ``(t, decoded)`` over `topic`: t in s of simulation time, decoded a dict
        for JSON channels and a protobuf message for Foxglove schemas. Log-time order for a
        complete file, file order (= write order) otherwise. KeyError for an unknown topic.
        """
        if topic not in self.topics:
            raise KeyError(f"no topic {topic!r} in {self.path} (has {sorted(self.topics)})")
        return self._iter_messages(topic)

    def _iter_messages(self, topic: str) -> Iterator[tuple[float, Any]]:
        factories = [ProtobufDecoderFactory(), JsonDecoderFactory()]
        with open(self.path, "rb") as f:
            if self.complete:
                seeking = SeekingReader(
                    f, decoder_factories=factories, record_size_limit=_RECORD_SIZE_LIMIT
                )
                for _, _, message, decoded in seeking.iter_decoded_messages(
                    topics=[topic], log_time_order=True
                ):
                    yield message.log_time / 1e9, decoded
                return
            stream = NonSeekingReader(
                f, decoder_factories=factories, record_size_limit=_RECORD_SIZE_LIMIT
            )
            try:
                for _, _, message, decoded in stream.iter_decoded_messages(
                    topics=[topic], log_time_order=False
                ):
                    yield message.log_time / 1e9, decoded
            except _BROKEN:
                return  # the torn end of a killed writer's file


class JsonDecoderFactory(McapDecoderFactory):
    """Decodes ``json``-encoded channels into Python objects."""

    def decoder_for(
        self, message_encoding: str, schema: Schema | None
    ) -> Callable[[bytes], Any] | None:
        return json.loads if message_encoding == "json" else None


def read_log(path: str | Path) -> RunLog:
    """Read the summary, metadata and attachments of the log at `path`.

    Messages are decoded lazily by `RunLog.messages`. A file without a usable summary is
    scanned front to back up to its first broken record. Raises LogReadError if `path` is not
    an MCAP file, FileNotFoundError if it does not exist.
    """
    path = Path(path)
    with open(path, "rb") as f:
        try:
            return _read_indexed(path, f)
        except _BROKEN:
            f.seek(0)
            return _read_scanning(path, f)


def _read_indexed(path: Path, f: IO[bytes]) -> RunLog:
    reader = SeekingReader(f, record_size_limit=_RECORD_SIZE_LIMIT)
    summary = reader.get_summary()
    if summary is None or summary.statistics is None:
        raise McapError("no summary statistics")
    stats = summary.statistics
    infos = {}
    for channel in summary.channels.values():
        schema = summary.schemas.get(channel.schema_id)
        infos[channel.topic] = TopicInfo(
            topic=channel.topic,
            schema_name=schema.name if schema else "",
            schema_encoding=schema.encoding if schema else "",
            message_encoding=channel.message_encoding,
            message_count=stats.channel_message_counts.get(channel.id, 0),
        )
    metadata = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
    attachments = {a.name: bytes(a.data) for a in reader.iter_attachments()}
    has_messages = stats.message_count > 0
    return RunLog(
        path=path,
        complete=True,
        metadata=metadata,
        attachments=attachments,
        topics=infos,
        start_time=stats.message_start_time / 1e9 if has_messages else None,
        end_time=stats.message_end_time / 1e9 if has_messages else None,
    )


def _read_scanning(path: Path, f: IO[bytes]) -> RunLog:
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    counts: dict[int, int] = {}
    metadata: dict[str, dict[str, str]] = {}
    attachments: dict[str, bytes] = {}
    start: int | None = None
    end: int | None = None
    for record in _surviving_records(path, f):
        if isinstance(record, Message):
            counts[record.channel_id] = counts.get(record.channel_id, 0) + 1
            start = record.log_time if start is None else min(start, record.log_time)
            end = record.log_time if end is None else max(end, record.log_time)
        elif isinstance(record, Schema):
            schemas[record.id] = record
        elif isinstance(record, Channel):
            channels[record.id] = record
        elif isinstance(record, Metadata):
            metadata[record.name] = dict(record.metadata)
        elif isinstance(record, Attachment):
            attachments[record.name] = bytes(record.data)
    infos = {}
    for channel in channels.values():
        schema = schemas.get(channel.schema_id)
        infos[channel.topic] = TopicInfo(
            topic=channel.topic,
            schema_name=schema.name if schema else "",
            schema_encoding=schema.encoding if schema else "",
            message_encoding=channel.message_encoding,
            message_count=counts.get(channel.id, 0),
        )
    return RunLog(
        path=path,
        complete=False,
        metadata=metadata,
        attachments=attachments,
        topics=infos,
        start_time=None if start is None else start / 1e9,
        end_time=None if end is None else end / 1e9,
    )


def _surviving_records(path: Path, f: IO[bytes]) -> Iterator[Any]:
    """Records of the data section in file order, up to its end or the first broken record.

    Chunks are expanded into their records; the summary section (which repeats schemas and
    channels) is not read. LogReadError if not even the magic and header
    can be read.
    """
    records = StreamReader(f, record_size_limit=_RECORD_SIZE_LIMIT).records
    try:
        header = next(records)
    except (*_BROKEN, StopIteration) as exc:
        raise LogReadError(path, f"{type(exc).__name__}: {exc}") from exc
    if not isinstance(header, Header):
        raise LogReadError(path, f"first record is a {type(header).__name__}, not a Header")
    yield header
    try:
        for record in records:
            if isinstance(record, DataEnd | Footer):
                return
            yield record
    except _BROKEN:
        return


def recover_log(path: str | Path, out_path: str | Path | None = None) -> Path:
    """Rewrite the log at `path` into a complete, indexed MCAP file and return its path.

    Every record that survived (schemas, channels, messages, metadata, attachments) is kept
    in file order; a metadata record ``recovered`` notes the source. `out_path` defaults to
    ``<stem>.recovered.mcap`` beside `path`; it may equal `path` (replaced atomically). Works
    on complete files too (a plain rewrite).
    """
    path = Path(path)
    out = Path(out_path) if out_path is not None else path.with_name(f"{path.stem}.recovered.mcap")
    fd, tmp_name = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent)
    try:
        with open(path, "rb") as src, os.fdopen(fd, "wb") as dst:
            _rewrite(path, src, dst)
        os.replace(tmp_name, out)
    except BaseException:
        Path(tmp_name).unlink(missing_ok=True)
        raise
    return out


def _rewrite(path: Path, src: IO[bytes], dst: IO[bytes]) -> None:
    writer = Writer(dst)
    schema_ids: dict[int, int] = {0: 0}
    channel_ids: dict[int, int] = {}
    kept = 0
    started = False
    for record in _surviving_records(path, src):
        if isinstance(record, Header):
            writer.start(profile=record.profile, library=f"locoplan {__version__} recover_log")
            started = True
        elif isinstance(record, Schema):
            schema_ids[record.id] = writer.register_schema(
                name=record.name, encoding=record.encoding, data=record.data
            )
        elif isinstance(record, Channel):
            channel_ids[record.id] = writer.register_channel(
                topic=record.topic,
                message_encoding=record.message_encoding,
                schema_id=schema_ids.get(record.schema_id, 0),
                metadata=dict(record.metadata),
            )
        elif isinstance(record, Message):
            if record.channel_id not in channel_ids:
                continue  # its channel record was lost: the message cannot be decoded
            writer.add_message(
                channel_id=channel_ids[record.channel_id],
                log_time=record.log_time,
                data=record.data,
                publish_time=record.publish_time,
                sequence=record.sequence,
            )
            kept += 1
        elif isinstance(record, Metadata):
            writer.add_metadata(record.name, dict(record.metadata))
        elif isinstance(record, Attachment):
            writer.add_attachment(
                create_time=record.create_time,
                log_time=record.log_time,
                name=record.name,
                media_type=record.media_type,
                data=record.data,
            )
    assert started, "_surviving_records yields the header first"
    writer.add_metadata(
        "recovered",
        {
            "source": str(path),
            "recovered_wall_time": dt.datetime.now(tz=dt.UTC).isoformat(timespec="seconds"),
            "messages_kept": str(kept),
        },
    )
    writer.finish()


def log_summary(path: str | Path) -> dict[str, Any]:
    """A JSON-ready overview of a log, for ``locoplan inspect``.

    Keys: path, complete, scenario, locoplan_version, start_wall_time, status (``finished``,
    ``aborted``, ``closed``, or None when the writer never closed the file), duration (s of
    simulation time covered by messages), start_time, end_time, message_count, topics
    ({topic: {"schema": name, "count": n}}), attachments (names), metrics (dict or None).
    """
    log = read_log(path)
    run = log.metadata.get(topics.METADATA_RUN, {})
    end = log.metadata.get(topics.METADATA_RUN_END, {})
    duration = (
        None if log.start_time is None or log.end_time is None else log.end_time - log.start_time
    )
    return {
        "path": str(log.path),
        "complete": log.complete,
        "scenario": run.get("scenario"),
        "locoplan_version": run.get("locoplan_version"),
        "start_wall_time": run.get("start_wall_time"),
        "status": end.get("status"),
        "duration": duration,
        "start_time": log.start_time,
        "end_time": log.end_time,
        "message_count": sum(info.message_count for info in log.topics.values()),
        "topics": {
            name: {"schema": info.schema_name, "count": info.message_count}
            for name, info in sorted(log.topics.items())
        },
        "attachments": sorted(log.attachments),
        "metrics": log.metrics,
    }
