"""
The bag: rosbag2-compatible MCAP files, written, read, decoded and mended without ROS.

Its modules, each imported on its own (this face imports none of them, so that the recorder
does not load the reader, nor a reader the writer):

- `files`: a bag folder's files in the order they were written, the MCAP magic check, the one
  front-to-back stream of a file's records;
- `metadata`: rosbag2's metadata (Jazzy, version 9), inside each file and as a folder's
  metadata.yaml;
- `writer`: `BagWriter`, serialized messages into a bag with rosbag2's schemas;
- `cdr`: decoders of CDR messages compiled from a bag's schema text;
- `reader`: `read_run` (one run of the co-design loop) and `read_topics` (any topics);
- `recovery`: closing the files of a killed recorder, continuing a bag in its next file.

Nothing here imports rclpy, the nodes (`ros/`) or the reports (`analysis/`): any tool reads a
bag with this room and core alone. The writer finds message definitions through
ament_index_python (a plain Python package) in the packages on AMENT_PREFIX_PATH.
"""
