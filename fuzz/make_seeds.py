#!/usr/bin/env python3
"""Seed corpora for the harnesses, from real files, run from the repository root.

  python3 fuzz/make_seeds.py                 seeds from the project's own files (config/, a
                                             simulated drive) into fuzz/corpus/<target>/, and
                                             the dictionaries into fuzz/dict/ (both in git)
  python3 fuzz/make_seeds.py --shared DIR    seeds copied from ../shared/data into DIR/<target>/;
                                             fuzz/run.sh makes them at each run, as shared/data's
                                             README asks that its files stay out of the repository
"""
import os
import struct
import sys

SHARED = "../shared/data"
SHARED_OUT = sys.argv[2] if len(sys.argv) == 3 and sys.argv[1] == "--shared" else None
if len(sys.argv) > 1 and SHARED_OUT is None:
    sys.exit("usage: fuzz/make_seeds.py [--shared DIR]")


def payloads(pcap):
    """UDP and TCP payloads of a classic little-endian pcap (Ethernet, IPv4)."""
    data = open(pcap, "rb").read()
    at, out = 24, []
    while at + 16 <= len(data):
        incl = struct.unpack_from("<I", data, at + 8)[0]
        frame = data[at + 16:at + 16 + incl]
        at += 16 + incl
        if len(frame) < 34 or frame[12:14] != b"\x08\x00":
            continue
        ihl = (frame[14] & 15) * 4
        proto = frame[23]
        l4 = 14 + ihl
        if proto == 17:
            out.append(frame[l4 + 8:])
        elif proto == 6:
            off = (frame[l4 + 12] >> 4) * 4
            if len(frame) > l4 + off:
                out.append(frame[l4 + off:])
    return out


def write(root, target, name, data):
    d = os.path.join(root, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def put(target, name, data):
    """A seed made from the project's own files (fuzz/corpus/, in git)."""
    if SHARED_OUT is None:
        write(os.path.join("fuzz", "corpus"), target, name, data)


def put_shared(target, name, data):
    """A seed copied or cut from ../shared/data (made at each run, never in git)."""
    if SHARED_OUT is not None:
        write(SHARED_OUT, target, name, data)


if SHARED_OUT is not None and not os.path.isdir(SHARED):
    print(f"fuzz/make_seeds.py: {SHARED} is absent; no seeds from it", file=sys.stderr)
    sys.exit(0)


packet = open(f"{SHARED}/velodyne/hdl64e_s2_manual_sample_packet_1206B.bin", "rb").read()
framed = struct.pack("<H", len(packet)) + packet
put_shared("velodyne_stream_fuzz", "one_packet", framed)
put_shared("velodyne_stream_fuzz", "three_packets", framed * 3)

grp = b"".join(payloads(f"{SHARED}/applanix/clearpath_basic_data_smoke.pcap"))
for i in range(4):
    put_shared("applanix_stream_fuzz", f"capture_{i}", grp[i * 3000:(i + 1) * 3000])

# Capture files: the head of the real Applanix capture (TCP), and the sample Velodyne packet in
# a one-record capture (Ethernet, IPv4, UDP to port 2368) that a truncation corrupts.
capture = open(f"{SHARED}/applanix/clearpath_basic_data_smoke.pcap", "rb").read()
put_shared("pcap_file_fuzz", "applanix_head", capture[:6000])
udp = struct.pack(">HHHH", 2368, 2368, 8 + len(packet), 0) + packet
ip = struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), 0, 0, 64, 17, 0,
                 bytes([192, 168, 3, 43]), bytes([255, 255, 255, 255]))
frame = b"\xff" * 6 + b"\x60\x76\x88\x00\x00\x00" + b"\x08\x00" + ip + udp
velodyne_pcap = (struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1) +
                 struct.pack("<IIII", 1700000000, 0, len(frame), len(frame)) + frame)
put_shared("pcap_file_fuzz", "velodyne_packet", velodyne_pcap)
put_shared("pcap_file_fuzz", "velodyne_packet_cut", velodyne_pcap[:-300])

put("can_text_fuzz", "vehicle.dbc", open("config/can/vehicle.dbc", "rb").read())
put("can_text_fuzz", "candump.log",
    b"(1700000000.000000) can0 123#DEADBEEF00112233\n(1700000000.010000) can0 1F0#0102\n"
    b"(1700000000.020000) can0 7FF##1112233\n\n")

# A KITTI raw drive's text files: an OXTS record with its times, and the IMU -> velodyne mounting.
put("kitti_text_fuzz", "oxts_and_times",
    b"49.015003823272 8.4342971002335 116.43032836914 0.035752 0.00903 -2.6087069803847 "
    b"-7.3848125497419 -11.167178269201 13.342774120196 0.18424810367317 -0.22164419262314 "
    b"-0.1253942541434 0.46617660707314 9.8105402154917 -0.14424584212937 0.43893620735698 "
    b"9.8244138656043 0.0087346616722958 -0.0031398713993441 0.0080013573264233 "
    b"0.0086669798207541 -0.0029914580263131 0.0082183398366087 0.26940243071706 "
    b"0.031710906736612 4 10 4 4 0\n2011-09-26 13:02:25.964389445\n")
put("kitti_text_fuzz", "calib_imu_to_velo",
    b"calib_time: 25-May-2012 16:47:16\nR: 9.999976e-01 7.553071e-04 -2.035826e-03 "
    b"-7.854027e-04 9.998898e-01 -1.482298e-02 2.024406e-03 1.482454e-02 9.998881e-01\n"
    b"T: -8.086759e-01 3.195559e-01 -7.997231e-01\n")

put("kitti_text_fuzz", "tracklet_labels.xml",
    b'<?xml version="1.0" encoding="UTF-8" standalone="yes" ?>\n<!DOCTYPE boost_serialization>\n'
    b'<boost_serialization signature="serialization::archive" version="9">\n'
    b'<tracklets class_id="0" tracking_level="0" version="0">\n<count>1</count>\n'
    b'<item_version>1</item_version>\n<item class_id="1" tracking_level="0" version="1">\n'
    b"<objectType>Car</objectType>\n<h>1.5</h>\n<w>1.8</w>\n<l>4.2</l>\n"
    b"<first_frame>0</first_frame>\n"
    b'<poses class_id="2" tracking_level="0" version="0">\n<count>1</count>\n'
    b'<item_version>2</item_version>\n<item class_id="3" tracking_level="0" version="2">\n'
    b"<tx>10.5</tx>\n<ty>-2.0</ty>\n<tz>-1.7</tz>\n<rx>0</rx>\n<ry>0</ry>\n<rz>0.25</rz>\n"
    b"<state>1</state>\n<occlusion>0</occlusion>\n<occlusion_kf>0</occlusion_kf>\n"
    b"<truncation>0</truncation>\n</item>\n</poses>\n<finished>1</finished>\n</item>\n"
    b"</tracklets>\n</boost_serialization>\n")

model = open("config/models/stac_default.stacmodel", "rb").read()
put("model_file_fuzz", "default_model_head", model[:4096])

# A dataset (format 5) of one track of one segment with its path and a snapshot; the harness
# writes this build's layout hashes and the checksum into inputs whose first byte is odd.
def dataset(version=5):
    names = [b"car", b"pedestrian", b"bicyclist"]
    b = b"STACDSET" + struct.pack("<IIII", version, 931, 940, 1) + struct.pack("<QQQ", 0, 0, 1)
    b += struct.pack("<I", len(names)) + b"".join(struct.pack("<I", len(n)) + n for n in names)
    b += b"\x01" + struct.pack("<I", 9) + b"drive.pcap"[:9]
    b += struct.pack("<QIIII", 7, 0, 0, 1, 0)
    b += struct.pack("<1871f", *[0.25 * (k % 17) for k in range(1871)])
    if version >= 5:
        b += struct.pack("<I2f", 1, 10.0, -4.0)
        b += struct.pack("<III8f", 1, 0, 2, 0.1, 0.2, 0.3, 40.0, -0.4, 0.0, 1.1, 9.0)
    return b + bytes(8)


put("dataset_file_fuzz", "one_track_v5", b"\x01" + dataset(5))
put("dataset_file_fuzz", "one_track_v4", b"\x01" + dataset(4))
put("dataset_file_fuzz", "raw_header", b"\x00" + dataset(5)[:200])

# Lines of a real `stac process` tracks file and `stac sim` truth file (fuzz/seeds/, kept small).
for name in ("tracks.jsonl", "truth.jsonl"):
    for k, line in enumerate(open(os.path.join("fuzz", "seeds", name), "rb").read().splitlines()):
        put("json_lines_fuzz", f"{name}_{k}", line)

# config_files_fuzz reads inputs of at most 8,448 bytes (fuzz/options): the configuration without
# its comments fits, the whole file and the HDL-64E's calibration are cut there; the HDL-32E
# and VLP-16 calibrations fit whole.
shipped = open("config/stac.yaml", "rb").read()
put("config_files_fuzz", "stac.yaml", shipped)
compact = []
for line in shipped.decode().splitlines():
    code = line.split(" #")[0].rstrip() if not line.lstrip().startswith("#") else ""
    if code.strip():
        compact.append(code)
put("config_files_fuzz", "stac_compact.yaml", ("\n".join(compact) + "\n").encode())
put_shared("config_files_fuzz", "calibration.yaml",
    open(f"{SHARED}/velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml", "rb").read())
for name in ("hdl32e.yaml", "vlp16.yaml"):
    put("config_files_fuzz", name, open(f"config/calib/{name}", "rb").read())
put_shared("calibration_xml_fuzz", "db.xml",
    open(f"{SHARED}/velodyne/calib/rosdrivers_64e_s2.1-sztaki_db.xml", "rb").read())
for name in ("veloview_HDL-64.xml", "veloview_HDL-32.xml", "veloview_VLP-16.xml"):
    put_shared("calibration_xml_fuzz", name, open(f"{SHARED}/velodyne/calib/{name}", "rb").read())

# gs_usb bulk-IN transfers: a received frame (20 bytes, no timestamp), a 24-byte one with a
# timestamp, an echo, and a CAN FD one; each behind its 1-byte length. Then the candleLight's
# BT_CONST (fclk 48 MHz, tseg1 1-16, tseg2 1-8, sjw 4, brp 1-1024, inc 1) at the head.
bt_const = struct.pack("<10I", 0, 48_000_000, 1, 16, 1, 8, 4, 1, 1024, 1)
received = struct.pack("<IIBBBB8s", 0xFFFFFFFF, 0x123, 8, 0, 0, 0, bytes(range(8)))
echo = struct.pack("<IIBBBB8s", 7, 0x1F0, 2, 0, 0, 0, b"\x01\x02" + bytes(6))
fd = struct.pack("<IIBBBB8s", 0xFFFFFFFF, 0x321, 8, 0, 0x02, 0, bytes(8))
put("gs_usb_frame_fuzz", "frames", b"\x00" + bt_const + b"".join(
    bytes([len(f)]) + f for f in (received, echo, fd)))
put("gs_usb_frame_fuzz", "frames_ts", b"\x01" + bt_const + bytes([24]) + received +
    struct.pack("<I", 123456))
put("candump_file_fuzz", "candump.log",
    b"(1700000000.000000) can0 123#DEADBEEF00112233\n(1700000000.010000) can0 1F0#0102\n"
    b"(1700000000.020000) can0 7FF#R\n(1700000000.030000) can0 12345678#00\n")

# The status cycle: the trailers' (type, value) bytes of a simulated S2.1 drive of 3.7 s, which
# carries the calibration dump twice (an S2.1 dump is used once the next one confirms it; the
# simulator sends the real S2.1 calibration); written
# when a built stac is found (build/tools/stac), model byte 1 (S2.1) first.
stac = "build/tools/stac"
if SHARED_OUT is None and os.path.exists(stac):
    import subprocess
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([stac, "sim", "--scenario", "highway", "--seed", "1", "--duration", "3.7",
                        "--out", f"{tmp}/s.pcap", "--truth", f"{tmp}/s.jsonl", "--calib",
                        f"{SHARED}/velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml"],
                       check=True, capture_output=True)
        trailers = b"".join(p[1204:1206] for p in payloads(f"{tmp}/s.pcap") if len(p) == 1206)
    put("velodyne_status_fuzz", "sim_s21_cycle", b"\x01" + trailers)
    put("velodyne_status_fuzz", "sim_s21_cycle_as_s3", b"\x02" + trailers[:2000])


def put_dict(target, words):
    if SHARED_OUT is not None:
        return
    d = os.path.join("fuzz", "dict")
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, f"{target}.dict"), "w") as f:
        for w in sorted(set(words)):
            f.write('"' + w.replace("\\", "\\\\").replace('"', '\\"') + '"\n')


# Dictionaries: the formats' keywords (libFuzzer -dict).
keys = []
for line in open("config/stac.yaml"):
    stripped = line.strip()
    if stripped and not stripped.startswith("#") and ":" in stripped:
        keys.append(stripped.split(":")[0].strip("- ") + ":")
keys += ["lasers:", "laser_id:", "rot_correction:", "vert_correction:", "dist_correction:"]
put_dict("config_files_fuzz", keys)
put_dict("calibration_xml_fuzz", ["<item>", "</item>", "<px>", "<id_>", "<rotCorrection_>",
                                  "<vertCorrection_>", "<distCorrection_>", "<distCorrectionX_>",
                                  "<distCorrectionY_>", "<vertOffsetCorrection_>",
                                  "<horizOffsetCorrection_>", "<focalDistance_>", "<focalSlope_>",
                                  "<enabled_>", "<intensity_>", "<minIntensity_>",
                                  "<maxIntensity_>", "<points_>", "<count>", "<distLSB_>"])
put_dict("can_text_fuzz", ["VERSION", "NS_", "BS_:", "BU_:", "BO_", "SG_", "CM_", "BA_DEF_", "BA_",
                           "VAL_", "SIG_VALTYPE_", "@1+", "@0-", "|", "#", "##", "can0", "(", ")"])
put_dict("json_lines_fuzz", ['"scan"', '"time"', '"end_time"', '"ego"', '"segments"', '"tracks"',
                             '"objects"', '"box"', '"origin"', '"class"', '"log_odds"', '"state"',
                             '"truth"', '"id"', "null", "true", "false", "1e308", "-0"])
put_dict("applanix_stream_fuzz", ["$GRP", "$MSG", "$#"])
put_dict("kitti_text_fuzz", ["R:", "T:", "R0_rect:", "Tr_velo_to_cam:", "calib_time:", "nan", "inf",
                             "1e308", "-", ":", ".", "<boost_serialization>", "<tracklets>",
                             "<item>", "</item>", "<count>", "<poses>", "<objectType>", "<tx>",
                             "<rz>", "<first_frame>", "Car", "Pedestrian", "DontCare"])
put_dict("dataset_file_fuzz", ["STACDSET", "car", "pedestrian", "bicyclist", "background"])
