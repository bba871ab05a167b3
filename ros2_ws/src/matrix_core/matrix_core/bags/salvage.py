"""Reading a bag that is damaged or was never finished: what it holds before the damage, then a clear error.

A rosbag2 MCAP bag is readable by ``rosbags`` only when it is whole: its ``metadata.yaml`` and the MCAP
summary at the end of the file index every message. A bag cut short (a copy that stopped, a full disk) or
left by a writer that was killed has neither; one with overwritten bytes may break in the middle. Here the
messages are then read from the MCAP records themselves, in file order (the order this project's writers
and the recorder write in, bag time), up to the first record that cannot be parsed, and
:class:`BagDamaged` says where it stopped and why. A frame cut by the damage is never handed out in part:
readers group by time and the group being read when the error comes is dropped.

Not detectable: bytes changed inside a message's payload (rosbags writes MCAP chunks without a CRC); the
message is handed out as it is, and its consumer checks it as any input (a corrupt image is refused there).
"""

from pathlib import Path

from rosbags.rosbag2 import Reader


class BagDamaged(Exception):
    """A bag could not be read to its end; the message says how many messages came before the damage."""


def mcap_file(bag) -> Path:
    """The one ``*.mcap`` file of a bag folder (or ``bag`` itself when it is that file)."""
    bag = Path(bag)
    if bag.is_file():
        return bag
    found = sorted(bag.glob('*.mcap')) if bag.is_dir() else []
    if len(found) != 1:
        raise BagDamaged(f'{bag}: not a readable rosbag2 folder and no single .mcap file in it ({len(found)} found)')
    return found[0]


def _open(bag):
    """An opened rosbags Reader, or the reason the bag cannot be opened whole."""
    try:
        reader = Reader(Path(bag))
        reader.open()
        return reader, ''
    except Exception as exc:  # rosbags raises ReaderError, but also ValueError/KeyError on broken summaries
        return None, f'{type(exc).__name__}: {exc}'


def connections(bag) -> dict:
    """topic -> message type of a bag, read from its MCAP records when the bag cannot be opened whole."""
    reader, why = _open(bag)
    if reader is not None:
        try:
            return {c.topic: c.msgtype for c in reader.connections}
        finally:
            reader.close()
    found = {}
    try:
        for topic, msgtype, _, _ in _stream(bag, None, why, channels_only=found):
            pass
    except BagDamaged:
        pass
    return found


def topic_counts(bag) -> tuple:
    """({topic: (message type, message count)}, damage): of the whole bag and '' when it reads whole, else
    of the messages before the damage and the :class:`BagDamaged` text."""
    from matrix_core.bags.reader import bag_topics

    try:
        return bag_topics(bag), ''
    except Exception:  # cut short, overwritten, unfinished: count what can still be read
        counts = {}
        try:
            for topic, msgtype, _, _ in raw_messages(bag):
                counts[topic] = (msgtype, counts.get(topic, (msgtype, 0))[1] + 1)
        except BagDamaged as exc:
            return counts, str(exc)
        return counts, ''


def raw_messages(bag, topics=None):
    """Yield (topic, message type, bag time ns, serialized CDR bytes) of every message of ``topics`` (all
    when None) in bag-time order. A bag that cannot be read to its end yields the messages before the damage
    (from its MCAP records, in file order, when it cannot even be opened), then raises :class:`BagDamaged`."""
    reader, why = _open(bag)
    if reader is None:
        yield from _stream(bag, topics, why)
        return
    count = 0
    try:
        wanted = [c for c in reader.connections if topics is None or c.topic in set(topics)]
        for conn, time_ns, raw in reader.messages(connections=wanted):
            yield conn.topic, conn.msgtype, time_ns, bytes(raw)
            count += 1
    except Exception as exc:  # a record that does not parse in the middle of an indexed bag
        raise BagDamaged(f'{bag}: damaged after {count} messages: {type(exc).__name__}: {exc}') from None
    finally:
        reader.close()


def _stream(bag, topics, why: str, channels_only: dict = None):
    """The MCAP records of ``bag`` in file order (see the module docstring); ``channels_only``: fill it with
    topic -> type and yield nothing."""
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader

    path = mcap_file(bag)
    schemas, channels, count = {}, {}, 0
    try:
        for record in StreamReader(str(path), validate_crcs=True).records:
            if isinstance(record, Schema):
                schemas[record.id] = record.name
            elif isinstance(record, Channel):
                channels[record.id] = (record.topic, schemas.get(record.schema_id, ''))
                if channels_only is not None:
                    channels_only[record.topic] = channels[record.id][1]
            elif isinstance(record, Message) and channels_only is None:
                topic, msgtype = channels[record.channel_id]
                if topics is None or topic in topics:
                    yield topic, msgtype, record.log_time, bytes(record.data)
                    count += 1
    except Exception as exc:  # EndOfFile (cut short), InvalidMagic, a record that does not parse
        raise BagDamaged(
            f'{bag} cannot be opened as a whole bag ({why}); read from {path.name} record by record: '
            f'{count} messages before the damage ({type(exc).__name__}: {exc or "end of file"})'
        ) from None
    raise BagDamaged(
        f'{bag} cannot be opened as a whole bag ({why}); read from {path.name} record by record: '
        f'all {count} messages (its records are intact)'
    )
