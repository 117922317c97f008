#pragma once
// Helpers shared by the report tests: figure files read back.
#include <gtest/gtest.h>

#include <QFile>
#include <QImage>
#include <QString>
#include <QXmlStreamReader>
#include <filesystem>

namespace csw::report {

inline QImage LoadPng(const std::filesystem::path& path) {
  QImage image(QString::fromStdString(path.string()));
  return image.convertToFormat(QImage::Format_RGB32);
}

// The SVG parsed as XML (failing the test on a parse error) and all its text.
inline QString SvgText(const std::filesystem::path& path) {
  QFile file(QString::fromStdString(path.string()));
  EXPECT_TRUE(file.open(QIODevice::ReadOnly)) << path;
  QXmlStreamReader xml(&file);
  QString text;
  bool svg_root = false;
  while (!xml.atEnd()) {
    xml.readNext();
    if (xml.isStartElement() && xml.name() == QStringLiteral("svg")) svg_root = true;
    if (xml.isCharacters()) text += xml.text().toString() + "\n";
  }
  EXPECT_FALSE(xml.hasError()) << path << ": " << xml.errorString().toStdString();
  EXPECT_TRUE(svg_root) << path;
  return text;
}

}  // namespace csw::report
