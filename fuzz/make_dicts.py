#!/usr/bin/env python3
"""Writes fuzz/dict/<format>.dict (libFuzzer/AFL dictionaries): the syntax of each format by
hand, plus the words its reader looks for, taken from the string literals of the reader's
source (keys, column names, element names, keywords), so that the fuzzer reaches past "unknown
key" on its first mutations. Run from the repository root after changing a reader."""
import os, re

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
D = os.path.join(ROOT, "fuzz", "dict")
os.makedirs(D, exist_ok=True)


def literals(*files, pattern=r"^[A-Za-z_][A-Za-z0-9_.]{1,40}$"):
    out = set()
    for f in files:
        text = open(os.path.join(ROOT, f), encoding="utf-8").read()
        for s in re.findall(r'"((?:[^"\\\n]|\\.)*)"', text):
            if re.match(pattern, s) and not s.endswith((".hpp", ".h")):
                out.add(s)
    return out


def esc(s):
    return "".join(c if 32 <= ord(c) < 127 and c not in '"\\' else "\\x%02X" % ord(c) if ord(c) < 256 else c
                   for c in s)


def write(name, words, comment):
    words = sorted(set(w for w in words if w))
    with open(os.path.join(D, name + ".dict"), "w", encoding="utf-8") as f:
        f.write(f"# {comment}\n# Written by fuzz/make_dicts.py.\n")
        for w in words:
            f.write(f'"{esc(w)}"\n')


numbers = ["0", "1", "-1", "1.5", "1e308", "1e-308", "-0", "nan", "NaN", "inf", "-inf", "1e999", "2147483648",
           "4294967296", "9223372036854775808", "0x10", "1,5", "."]
write("ply", ["ply", "format", "ascii", "binary_little_endian", "binary_big_endian", "1.0", "element", "vertex", "face",
              "property", "list", "end_header", "comment", "obj_info", "x", "y", "z", "\n", "\r\n"]
      + ["char", "uchar", "short", "ushort", "int", "uint", "float", "double", "int8", "uint8", "int16", "uint16",
         "int32", "uint32", "float32", "float64"] + numbers, "PLY headers and numbers")
write("points", numbers + [" ", ",", "\t", "#", "\n", "\r\n", "\xef\xbb\xbf"], "XYZ and NIST .ds point lists")
write("csv", numbers + [",", ";", "#", "\n", "\r\n", "\xef\xbb\xbf"]
      + list(literals("evaluate/ingest.cpp", "evaluate/point_cloud.cpp", "evaluate/ttp_ingest.cpp",
                      "model/dataset.cpp", "core/csv.cpp")), "CSV files: separators, numbers, the columns the readers ask for")
write("probe_log", numbers + ["PT", "START", "%", " ", "\n", "20260131", "235959", "- ", "  "],
      "controller probe logs (LinuxCNC LOG, Fanuc DPRNT)")
yaml_syntax = [": ", "- ", "\n", "  ", "[", "]", "{", "}", ", ", "&a", "*a", "!!str", "|", ">", "'", "#", "---", "...",
               "~", "null", "true", "false", ".nan", ".inf", "-.inf", " mm", " um", " m", " deg", " rad", " s", " min",
               " h", " K", " C", " um/m", " rpm", " mm/min"]
yaml_sources = [os.path.join(d, f) for d in ("parts", "sim") for f in os.listdir(os.path.join(ROOT, d))
                if f.endswith(".cpp") and not f.endswith("_test.cpp")] + ["core/units.cpp"]
write("yaml", yaml_syntax + numbers + list(literals(*yaml_sources)), "YAML descriptions: syntax, units, every key the loaders know")
write("json", ["{", "}", "[", "]", ":", ",", '"', "true", "false", "null", "\\u0000", "\\ud800"] + numbers
      + ['"%s"' % w for w in literals("parts/plan_manifest.cpp", "parts/sw_compensation.cpp")],
      "JSON: syntax and the manifest's and compensation file's keys")
write("gum_expression", ["+", "-", "*", "/", "^", "(", ")", ",", "pi", "sqrt(", "exp(", "log(", "log10(", "sin(", "cos(",
                         "tan(", "asin(", "acos(", "atan(", "abs(", "atan2(", "pow(", "hypot(", "x", "y", "z", "l_s",
                         "theta", "e-6", "E+3"] + numbers, "GUM measurement-model expressions")
gcode_common = ["G0", "G1", "G2", "G3", "G4", "G10", "L2", "G17", "G21", "G40", "G43", "H1", "G49", "G53", "G54", "G59",
                "G80", "G90", "G91", "G94", "M0", "M2", "M3", "M4", "M5", "M6", "M8", "M9", "M30", "T1", "S1000", "F100",
                "X", "Y", "Z", "B", "C", "I", "J", "K", "P", "R", "Q", "N10", "#1", "#5061", "#500", "=", "[", "]",
                "(", ")", "\n", " EQ ", " NE ", " GT ", " LT ", " GE ", " LE ", " AND ", " OR ", " XOR ", " MOD ",
                "SIN", "COS", "TAN", "ATAN", "SQRT", "ABS", "ROUND", "FIX", "FUP", "LN", "EXP", "/"] + numbers
write("gcode_linuxcnc", gcode_common + ["G38.2", "G38.3", "o100", " sub", " endsub", " call", " while", " endwhile",
                                        " do", " if", " elseif", " else", " endif", " break", " continue", " return",
                                        "#<x>", "#<_x>", "#5070", "(LOGOPEN,", "(LOG,", "(LOGCLOSE)", "(ABORT,",
                                        "(MSG,", "(DEBUG,", ";", "EXISTS", "%"] + list(literals("gcode/interpreter.cpp")),
      "LinuxCNC RS274NGC")
write("gcode_fanuc", gcode_common + ["G31", "WHILE", "DO1", "END1", "DO2", "END2", "IF", "GOTO", "THEN", "#3000",
                                     "#3011", "#3012", "POPEN", "DPRNT[", "PCLOS", "*", "[53]", "O0001", "%", "M98",
                                     "M99"] + list(literals("gcode/interpreter.cpp")), "Fanuc macro B")
qif_words = literals("interop/qif.cpp", pattern=r"^[A-Za-z][A-Za-z0-9_:]{1,40}$")
write("qif", ["<", ">", "</", "/>", "=\"", "\"", "<?xml version=\"1.0\"?>", "<!DOCTYPE ", "<!ENTITY ", "&", ";",
              "<![CDATA[", "]]>", "xmlns=\"http://qifstandards.org/xsd/qif3\"", "versionQIF=\"3.0.0\"", "id=\"1\"",
              "n=\"", "linearUnit"] + ["<%s>" % w for w in qif_words] + ["</%s>" % w for w in qif_words] + numbers,
      "QIF 3.0 XML: syntax and the elements the reader knows")
write("dmis", ["/", ",", "(", ")", "=", "$\n", "\n", "'", "$$", "F(", "FA(", "DMISMN/", "ENDFIL", "UNITS/MM,ANGDEC",
               "FEAT/", "MEAS/", "ENDMES", "PTMEAS/CART,", "GOTO/", "OUTPUT/", "CART", "INNER", "OUTER", "SPHERE",
               "PLANE", "CYLNDR", "CIRCLE"] + list(literals("interop/dmis.cpp", pattern=r"^[A-Z][A-Z0-9_/]{1,20}$"))
      + numbers, "DMIS programs and outputs")
print("dictionaries written under", D)
